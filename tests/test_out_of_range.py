"""The input-range policy: which values are out of range (hand-worked bounds), reject / warn /
clip, the report of what was clipped, NaN/Inf, run_program's boundaries and ``--clip``."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends import save
from backends.reference import RunOptions, run_program, simulate
from backends.reference.encoding import encode_inputs
from backends.reference.input_range import OutOfRangeWarning, out_of_range
from compiler.compile import compile_graph
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    RateCode,
    SpikingNetwork,
)
from ir import Graph
from ir.errors import IRError, SimulationError
from radarsnn.cli import main


def one_layer_net(code, split: str = "none", decoder: str = "spike_time") -> SpikingNetwork:
    """Three inputs (split per ``split``) into one fire-once neuron read by ``decoder``."""
    parts = {"part": 2} if split != "none" else {}
    return SpikingNetwork(
        name="n", n_steps=10,
        populations=[Population(id="a", shape={"i": 3, **parts}, source=True),
                     Population(id="b", shape={"o": 1},
                                params=NeuronParams(du=0.0, v_th=1.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="a", target="b",
                                      contract=("i", *parts), produce=("o",),
                                      weights=np.ones((3 * (2 if parts else 1), 1)))],
        encoders=[Encoder(port="x", population="a", code=code, split=split)],
        decoders=[Decoder(port="y", population="b", kind=decoder,
                          **({"t_ref": 10.0} if decoder == "spike_time" else {}))])


LINEAR = LatencyCode(t_max=8, x_min=0.0, x_max=1.0)  # one step = 1/8: x* = 1 + 1/16


def test_latency_bound_is_half_a_step_above_x_max():
    parts = np.array([[1.0, 1.0625, 1.0626, -5.0, 0.0]])
    assert out_of_range(LINEAR, parts, 0, 10).tolist() == [[False, False, True, False, False]]
    floor = LINEAR.model_copy(update={"rounding": "floor"})
    assert out_of_range(floor, parts, 0, 10).tolist() == [[False, True, True, False, False]]
    log = LatencyCode(kind="log", t_max=4, x_min=1.0, x_max=16.0)  # step = ln 2: x* = 16·√2
    assert out_of_range(log, np.array([22.6, 22.7, 0.5]), 0, 10).tolist() == [False, True, False]
    threshold = LatencyCode(t_max=1, x_min=0.5, x_max=1.5, rounding="floor")
    assert not out_of_range(threshold, np.array([1e9, -1e9]), 0, 10).any()


def test_rate_bound_is_one_more_spike():
    code = RateCode(x_min=0.0, x_max=1.0, max_rate=0.5)  # 10 steps: 5 spikes at x_max
    # x = 1.1 -> rate 0.55 -> floor(5.5) = 5: no change; x = 1.2 -> 6 spikes: out
    assert out_of_range(code, np.array([1.1, 1.2]), 0, 10).tolist() == [False, True]


@given(st.lists(st.floats(-4, 4), min_size=3, max_size=3))
def test_in_range_values_encode_exactly_like_their_clipped_values(values):
    x = np.array(values)
    inside = ~out_of_range(LINEAR, x[None, :], 0, 10)[0]
    clipped = np.clip(x, LINEAR.x_min, LINEAR.x_max)
    raw_steps = np.rint(LINEAR.t_min + (LINEAR.x_max - x) / (LINEAR.x_max - LINEAR.x_min)
                        * (LINEAR.t_max - LINEAR.t_min))
    # a step >= t_max is "no spike": below x_min is the code's floor, like x_min itself
    emitted = np.clip(raw_steps, LINEAR.t_min, LINEAR.t_max)
    np.testing.assert_array_equal(emitted[inside], LINEAR.spike_steps(clipped)[inside])


def test_reject_names_port_count_index_value_and_range():
    net = one_layer_net(LINEAR, split="signed")
    x = np.array([[0.5, 3.0, -2.0], [0.1, 0.2, 0.3]])  # frame 0: 3.0 and |-2.0| are out
    with pytest.raises(SimulationError) as info:
        simulate(net, {"x": x}, out_of_range="reject")
    message = str(info.value)
    assert info.value.node == "x"
    for part in ("input 'x'", "2 of 6 values", "[0, 1]", "index (0, 1)", "value 3"):
        assert part in message, message


def test_reject_is_the_default_warn_and_clip_on_request_are_counted():
    net = one_layer_net(LINEAR)
    x = np.array([0.5, 3.0, 0.25])
    with pytest.raises(SimulationError, match=r"1 of 3 values .* first at index \(1,\) "
                                              r"\(value 3\)"):
        simulate(net, {"x": x})
    with pytest.raises(SimulationError, match="input 'x'"):
        encode_inputs(net, {"x": x})
    with pytest.warns(OutOfRangeWarning, match="1 of 3 values"):
        warned = simulate(net, {"x": x}, out_of_range="warn")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        clipped = simulate(net, {"x": x}, out_of_range="clip")
    inside = simulate(net, {"x": np.clip(x, 0.0, 1.0)})
    assert warned.clipped == clipped.clipped == {"x": 1} and inside.clipped == {}
    np.testing.assert_array_equal(clipped.outputs["y"], inside.outputs["y"])
    assert "input x: 1 values outside the encoder's range, clipped" in clipped.summary()


def test_the_error_names_what_the_range_applies_to_and_the_ways_out():
    with pytest.raises(SimulationError) as info:
        simulate(one_layer_net(LINEAR, split="signed"), {"x": np.array([0.5, -3.0, 0.25])})
    message = str(info.value)
    for part in ("[0, 1] (per sign: |x|)", "value -3", "headroom", "out_of_range='clip'",
                 "--clip"):
        assert part in message, message


def _two_ports() -> SpikingNetwork:
    """Ports ``x`` and ``z`` (both LINEAR) into one neuron."""
    src = [Population(id=p, shape={"i": 2}, source=True) for p in ("a", "c")]
    return SpikingNetwork(
        name="two", n_steps=10,
        populations=[*src, Population(id="b", shape={"o": 1},
                                      params=NeuronParams(du=0.0, v_th=1.0, reset="fire_once"))],
        projections=[MatrixProjection(id=f"w{p}", source=p, target="b", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1))) for p in "ac"],
        encoders=[Encoder(port="x", population="a", code=LINEAR),
                  Encoder(port="z", population="c", code=LINEAR)],
        decoders=[Decoder(port="y", population="b", kind="spike_time", t_ref=10.0)])


def test_a_mapping_sets_the_policy_per_port_and_ports_left_out_reject():
    net, big, fine = _two_ports(), np.array([2.0, 0.5]), np.array([0.5, 0.5])
    assert simulate(net, {"x": big, "z": fine}, out_of_range={"x": "clip"}).clipped == {"x": 1}
    with pytest.raises(SimulationError, match="input 'z': 1 of 2 values"):
        simulate(net, {"x": big, "z": big}, out_of_range={"x": "clip"})
    both = simulate(net, {"x": big, "z": big}, out_of_range={"x": "clip", "z": "clip"})
    assert both.clipped == {"x": 1, "z": 1}


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("policy", ["reject", "warn", "clip"])
def test_nan_and_inf_are_refused_under_every_policy(bad, policy):
    with pytest.raises(SimulationError, match=r"1 of 3 values are NaN or Inf, first at index "
                                              r"\(2,\)"):
        simulate(one_layer_net(LINEAR), {"x": np.array([0.5, 0.5, bad])}, out_of_range=policy)


def test_unknown_policy_is_refused():
    with pytest.raises(SimulationError, match="out_of_range='wrap'"):
        simulate(one_layer_net(LINEAR), {"x": np.zeros(3)}, out_of_range="wrap")


def _program():
    g = Graph.from_dict({"name": "p", "nodes": [
        {"id": "a", "op": "input", "shape": {"range": 8}, "domain": "power"},
        {"id": "c", "op": "cfar", "input": "a", "kind": "ca", "guard": 0, "train": 1,
         "alpha": 1.5},
        {"id": "o", "op": "output", "input": "c"}]})
    x = np.linspace(0.1, 1.0, 8)
    # the CFAR code topped at the calibration maximum: not a saturating code
    # (tests/test_saturating_codes.py), so values above it are the policy's to judge
    return compile_graph(g, target="loihi2", calibration_inputs={"a": x},
                         options={"cfar_quantiles": {"ca": [0.0, 1.0]}}), x


def test_run_program_applies_the_policy_to_the_callers_values():
    program, x = _program()
    assert run_program(program, {"a": x}, out_of_range="reject").clipped == {}
    with pytest.raises(SimulationError, match="input 'a'"):
        run_program(program, {"a": x * 10}, out_of_range="reject")
    with pytest.raises(SimulationError, match="input 'a'"):  # the default
        run_program(program, {"a": x * 10})
    with pytest.raises(SimulationError, match="input 'a'"):  # the policy in the one record
        run_program(program, {"a": x * 10}, options=RunOptions(out_of_range="reject"))
    assert run_program(program, {"a": x * 10}, out_of_range="clip").clipped["a"] > 0
    with pytest.raises(IRError, match="non-finite"):
        run_program(program, {"a": np.full(8, np.inf)}, out_of_range="clip")


def test_cli_run_rejects_by_default_warns_or_clips_on_request(tmp_path, capsys):
    program, x = _program()
    save(program, tmp_path / "art")
    np.save(tmp_path / "big.npy", x * 10)
    art, big = str(tmp_path / "art"), str(tmp_path / "big.npy")
    assert main(["run", art, "-i", big, "-q"]) == 1  # a stronger scene is refused, as documented
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: input 'a': ")
    assert re.search(r"\d+ of 8 values are above", err[0]) and "--clip" in err[0]
    assert main(["run", art, "-i", big, "--out-of-range", "reject"]) == 1
    assert capsys.readouterr().err.startswith("error: input 'a'")
    assert main(["run", art, "-i", big, "-q", "--out-of-range", "warn"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warning: clipped to the calibrated encoder "
                                               "range: ") and "at 'a'" in err[0]
    assert "--out-of-range reject" in err[0] and "headroom" in err[0]
    np.save(tmp_path / "small.npy", x)
    assert main(["run", art, "-i", str(tmp_path / "small.npy"), "-q"]) == 0
    assert capsys.readouterr().err == ""  # nothing clipped: no warning
    assert main(["run", str(tmp_path / "art"), "-i", str(tmp_path / "big.npy"), "--clip",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["clipped"]["a"] > 0
