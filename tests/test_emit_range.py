"""Generated packages apply the out-of-range policy like the reference simulator: refuse by
default with one clear error (port, count, first index, value, range, the fix), clip on
request (``run(..., out_of_range="clip")``, ``python -m <package> --clip``), the same
values out of range as ``backends.reference.input_range`` (hand-worked bounds), and values
decoded from an upstream spiking segment always clipped."""

from __future__ import annotations

import importlib
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_out_of_range import one_layer_net

from backends.emit import emit_numpy
from backends.emit.run_package import run_package
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from compiler.snn import (
    LatencyCode,
    RateCode,
    SpikingNetwork,
)
from ir import Graph
from ir.errors import SimulationError

# x* = value_of(t_min - 1/2): 1 + 1/16 for both; t_min = 1 rounds 0.5 down to step 0 < t_min,
# so x* itself is out of range there (the reference's tie rule), not for t_min = 0.
CODES = {
    "even": LatencyCode(t_max=8, x_min=0.0, x_max=1.0),
    "odd": LatencyCode(t_min=1, t_max=9, x_min=0.0, x_max=1.0),
    "floor": LatencyCode(t_max=8, x_min=0.0, x_max=1.0, rounding="floor"),
    "dither": LatencyCode(t_max=8, x_min=0.0, x_max=1.0, rounding="dither"),
    "log": LatencyCode(kind="log", t_max=4, x_min=1.0, x_max=16.0),  # x* = 16·√2
    "rate": RateCode(x_min=0.0, x_max=1.0, max_rate=0.5),  # 10 steps: 5 spikes at x_max
    "threshold": LatencyCode(t_max=1, x_min=0.5, x_max=1.5, rounding="floor"),
}


def _net(code, split: str = "none") -> SpikingNetwork:
    return one_layer_net(code, split, decoder="count")


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    """Per code (and the signed split), the network and its generated package, imported."""
    folder = tmp_path_factory.mktemp("emit_range")
    nets = {key: _net(code) for key, code in CODES.items()}
    nets["signed"] = _net(CODES["even"], split="signed")
    sys.path.insert(0, str(folder))
    try:
        yield {key: (net, importlib.import_module(emit_numpy(net, folder, name=f"r_{key}").name))
               for key, net in nets.items()}
    finally:
        sys.path.remove(str(folder))
        for key in [k for k in sys.modules if k.startswith("r_")]:
            del sys.modules[key]


@pytest.mark.parametrize(("key", "values", "out"), [
    ("even", [1.0, 1.0625, 1.0626], [False, False, True]),
    ("odd", [1.0, 1.0624, 1.0625], [False, False, True]),
    ("floor", [1.0, 1.0 + 1e-12, -5.0], [False, True, False]),
    ("dither", [1.0, 1.0 + 1e-12, -5.0], [False, True, False]),  # floor(t + u), u may be 0
    ("log", [22.6, 22.7, 0.5], [False, True, False]),
    ("rate", [1.1, 1.2, -3.0], [False, True, False]),  # 1.2: floor(6.0) = 6 spikes > 5
    ("threshold", [1e9, -1e9, 0.0], [False, False, False]),
])
def test_hand_worked_bounds_are_the_references(packages, key, values, out):
    net, pkg = packages[key]
    x = np.array(values)
    want = int(np.sum(out))
    ref = simulate(net, {"x": x}, mode="step", out_of_range="clip")
    assert sum(ref.clipped.values()) == want
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = pkg.run({"x": x}, out_of_range="warn")
    np.testing.assert_array_equal(got["y"], ref.outputs["y"])
    assert [str(w.message).split(" values")[0] for w in caught] == (
        [f"input 'x': {want} of 3"] if want else [])
    if want:
        first = out.index(True)
        with pytest.raises(pkg.InputError, match=rf"first at index \({first},\)"):
            pkg.run({"x": x})
        with pytest.raises(SimulationError):
            simulate(net, {"x": x}, mode="step")
    else:
        np.testing.assert_array_equal(pkg.run({"x": x})["y"], ref.outputs["y"])


@given(st.lists(st.floats(-3.0, 40.0), min_size=6, max_size=6),
       st.sampled_from(sorted(CODES) + ["signed"]))
def test_the_package_refuses_exactly_what_the_reference_refuses(packages, values, key):
    net, pkg = packages[key]
    x = np.array(values).reshape(2, 3)  # two frames
    ref = simulate(net, {"x": x}, mode="step", out_of_range="clip")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # clip is silent
        np.testing.assert_array_equal(pkg.run({"x": x}, out_of_range="clip")["y"],
                                      ref.outputs["y"])
    if ref.clipped:
        with pytest.raises(pkg.InputError, match=rf"input 'x': {ref.clipped['x']} of 6 values"):
            pkg.run({"x": x})
    else:
        np.testing.assert_array_equal(pkg.run({"x": x})["y"], ref.outputs["y"])


def test_the_error_names_port_count_index_value_range_and_fix(packages):
    _, pkg = packages["signed"]
    x = np.array([[0.5, 0.25, 0.5], [0.1, -3.0, 2.0]])
    with pytest.raises(pkg.InputError) as info:
        pkg.run({"x": x})
    message = str(info.value)
    assert isinstance(info.value, ValueError)
    for part in ("input 'x'", "2 of 6 values", "[0, 1] (per sign: |x|)", "index (1, 1)",
                 "value -3", "out_of_range='clip'", "--clip"):
        assert part in message, message
    with pytest.raises(pkg.InputError, match="out_of_range='wrap' is not one of"):
        pkg.run({"x": x}, out_of_range="wrap")
    # a mapping per port; ports it leaves out are refused as by default
    assert pkg.run({"x": x}, out_of_range={"x": "clip"})["y"].shape == (2, 1)
    with pytest.raises(pkg.InputError, match="input 'x'"):
        pkg.run({"x": x}, out_of_range={"other": "clip"})


def test_the_command_line_refuses_in_one_line_and_clips_with_the_flag(packages):
    net, pkg = packages["even"]
    x = np.array([0.5, 3.0, 0.25])
    with pytest.raises(SimulationError) as info:
        run_package(pkg.__path__[0], {"x": x})
    lines = str(info.value).splitlines()
    assert "Traceback" not in str(info.value)
    assert lines[-1].startswith("error: input 'x': 1 of 3 values") and "--clip" in lines[-1]
    out, counts = run_package(pkg.__path__[0], {"x": x}, out_of_range="clip")
    ref = simulate(net, {"x": x}, mode="step", out_of_range="clip")
    np.testing.assert_array_equal(out["y"], ref.outputs["y"])
    assert counts == [ref.spike_counts]
    with pytest.raises(SimulationError, match="'reject' or 'clip'"):
        run_package(pkg.__path__[0], {"x": x}, out_of_range="warn")


def test_values_decoded_upstream_are_clipped_the_callers_are_refused(tmp_path):
    """x → spiking DFT → host |.|², Σrx → spiking CFAR, calibrated on noise.  The same tone
    on four receivers, inside x's range, sums coherently: Σrx is far above the noise's
    (incoherent) sums the CFAR code was calibrated on.  That value was decoded from spikes,
    so it is clipped under every policy (as ``run_program`` does); a 10× louder input is
    refused at x."""
    graph = Graph.from_dict({"name": "tone", "nodes": [
        {"id": "x", "op": "input", "shape": {"rx": 4, "sample": 32}},
        {"id": "rng", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range",
         "keep": "positive"},
        {"id": "mag", "op": "magnitude", "input": "rng", "kind": "square"},
        {"id": "pow", "op": "sum", "input": "mag", "axis": "rx"},
        {"id": "det", "op": "cfar", "input": "pow", "kind": "ca", "guard": 1, "train": 2,
         "alpha": 4.0},
        {"id": "out", "op": "output", "input": "det"}]})
    noise = np.random.default_rng(0).standard_normal((4, 4, 32))
    program = compile_graph(graph, "loihi2", calibration_inputs={"x": noise})
    tone = 2.0 * np.cos(2 * np.pi * 5 * np.arange(32) / 32) * np.ones((4, 1))
    assert np.abs(tone).max() < np.abs(noise).max()
    ref = run_program(program, {"x": tone}, mode="step")
    assert ref.clipped.get("pow", 0) > 0 and "x" not in ref.clipped
    pkg = emit_numpy(program, tmp_path, name="tone_pkg")
    out, counts = run_package(pkg, {"x": tone})
    np.testing.assert_array_equal(out["out"], ref.outputs["out"])
    # a detection mask is bool in both, as the interpreter gives it (the package wrote float64)
    assert out["out"].dtype == ref.outputs["out"].dtype == np.bool_
    assert out["out"][5] and counts == [s.spike_counts for s in ref.simulations]
    with pytest.raises(SimulationError, match="error: input 'x': "):
        run_package(pkg, {"x": 10 * tone})
    with pytest.raises(SimulationError, match="input 'x': "):
        run_program(program, {"x": 10 * tone})
