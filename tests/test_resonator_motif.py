"""The ``resonator`` DFT motif compiled end to end: accuracy against np.fft on ``unbounded``
and ``loihi2``, the fixed-point drift bound, resources beside the S-FT, and its errors."""

from __future__ import annotations

import numpy as np
import pytest

from backends import load, save
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from compiler.lowering import default_registry
from compiler.lowering.dft_common import sft_rmse
from compiler.report import build_report
from ir import Graph, evaluate
from ir.errors import BudgetError, CompileError
from radar.windows import window_coefficients

N = 64


def _graph(n: int = N, *, complex_in: bool = False, **dft) -> Graph:
    return Graph.from_dict({"name": "res", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 3, "sample": n}, "complex": complex_in},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", **dft},
        {"id": "o", "op": "output", "input": "f"}]})


def _signal(n: int = N, complex_in: bool = False) -> np.ndarray:
    rng = np.random.default_rng(0)
    t = np.arange(n)
    x = rng.normal(size=(3, n)) + 3 * np.cos(2 * np.pi * 5 * t / n)
    if complex_in:
        x = x + 1j * (rng.normal(size=(3, n)) + 3 * np.sin(2 * np.pi * 9 * t / n))
    return x


def _compile(target, graph=None, x=None, **options):
    x = _signal() if x is None else x
    return compile_graph(graph or _graph(keep="positive"), target, motifs={"f": "resonator"},
                         calibration_inputs={"x": x}, time_steps=256, options=options or None)


def test_registry_lists_the_motif_for_dft_only():
    described = default_registry().describe()
    assert "resonator" in described["dft"]["motifs"]
    assert described["dft"]["default"] == "time"  # existing chains unchanged
    assert "resonator" not in described["linear"]["motifs"]


@pytest.mark.parametrize("target", ["unbounded", "loihi2"])
@pytest.mark.parametrize("readout", ["time", "graded"])
def test_accuracy_against_numpy_fft(target, readout):
    x = _signal()
    if readout == "graded" and target == "unbounded":  # binary spikes: refused, named
        with pytest.raises(BudgetError, match="binary spikes only.*resonator_readout='log'"):
            _compile(target, x=x, resonator_readout=readout)
        return
    p = _compile(target, x=x, resonator_readout=readout)
    ref = np.fft.fft(x, axis=1)[:, :N // 2]
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    err = np.abs(y - ref).max() / np.abs(ref).max()
    # time read-out: half a step of 256 per part (plus 12-bit input levels, fixed-point drift)
    assert err < (0.006 if readout == "time" else 0.004), err
    assert sft_rmse(y, ref, n_fft=N) < 0.002
    assert p.networks[0].n_steps == N + (256 if readout == "time" else 1)


@pytest.mark.parametrize("readout", ["time", "auto"])
def test_complex_input_window_and_shift(readout):
    x = _signal(complex_in=True)
    g = _graph(complex_in=True, window="hann", shift=True)
    p = _compile("unbounded", graph=g, x=x, resonator_readout=readout)
    ref = np.fft.fftshift(np.fft.fft(x * window_coefficients("hann", N), axis=1), axes=1)
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    if readout == "time":  # linear: half a step of 256 of the calibrated peak per part
        assert np.abs(y - ref).max() / np.abs(ref).max() < 0.006
    else:  # auto on a host read-out without graded spikes: log, ±2.8 % of every part
        assert p.networks[0].meta["resonator"]["f"]["readout"] == "log"
        big = np.abs(ref) > 1e-2 * np.abs(ref).max()  # above the 12-bit input code's levels
        rel = np.abs(y[big] - ref[big]) / np.abs(ref[big])
        assert rel.max() < 0.04, rel.max()  # both parts within 2.8 %: |e| < 2.8 % · √2


def test_log_readout_keeps_a_new_target_in_a_bin_that_held_noise():
    # calibrated on a tone in bin 5, run on one in bin 20: per-bin maxima clip it, log not
    t = np.arange(N)
    rng = np.random.default_rng(1)
    cal = rng.normal(size=(3, N)) + 300 * np.cos(2 * np.pi * 5 * t / N)
    run = rng.normal(size=(3, N)) + 300 * np.cos(2 * np.pi * 20 * t / N)
    ref = np.fft.fft(run, axis=1)[:, :N // 2]
    for readout, keeps in (("time", False), ("log", True)):
        p = _compile("spinnaker2", x=cal, resonator_readout=readout)
        y = run_program(p, {"x": run}, mode="closed", out_of_range="clip").outputs["o"]
        ratio = np.abs(y[:, 20]) / np.abs(ref[:, 20])
        assert bool(np.all(np.abs(ratio - 1) < 0.03)) is keeps, (readout, ratio)


def test_fixed_point_engines_agree_and_drift_is_bounded():
    x = _signal()
    p = _compile("loihi2", x=x, resonator_coef_bits=16)  # the user's claim of wider products
    net = p.networks[0]
    drift = net.meta["resonator"]["f"]
    assert drift["coef_bits"] == 16 and drift["bound"] <= 0.01
    a = simulate(net, {"x": x}, mode="step", arithmetic="int64")
    b = simulate(net, {"x": x}, mode="closed", arithmetic="float64")
    np.testing.assert_array_equal(a.first_spike_steps["f/out"], b.first_spike_steps["f/out"])


def test_too_few_coefficient_bits_is_refused_naming_the_bound():
    with pytest.raises(CompileError, match=r"node 'f': resonator drift bound .* exceeds "
                                           r"resonator_drift_max=0.01 with 8-bit"):
        _compile("loihi2", resonator_coef_bits=8, resonator_drift_max=0.01)


def test_the_chip_format_is_kept_and_a_large_drift_reported():
    """Default: Lava's 12-bit RF coefficients, never widened; a bound over 0.01 is reported."""
    from compiler.lowering.resonator import ResonatorDriftWarning

    with pytest.warns(ResonatorDriftWarning, match=r"node 'f': resonator drift bound 0\.\d+ "
                                                  r"over N=\d+ steps with the chip's 12-bit"):
        p = _compile("loihi2", graph=_graph(keep="positive", n_fft=1024), x=_signal())
    drift = p.networks[0].meta["resonator"]["f"]
    assert drift["coef_bits"] == 12 and drift["bound"] > 0.01


def test_zero_padding_streams_zeros():
    x = _signal()
    p = _compile("loihi2", graph=_graph(keep="positive", n_fft=128), x=x)
    ref = np.fft.fft(x, n=128, axis=1)[:, :64]
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    assert p.networks[0].n_steps == 128 + 1  # 64 samples, 64 zeros, one graded step
    bound = p.networks[0].meta["resonator"]["f"]["bound"]  # over the 128 rotating steps
    assert np.abs(y - ref).max() / np.abs(ref).max() < bound + 0.002


def test_range_angle_chain_compiles_and_runs():
    # range DFT over samples, angle DFT over 8 virtual antennas zero-padded to 32 bins
    g = Graph.from_dict({"name": "ra", "nodes": [
        {"id": "adc", "op": "adc_input", "shape": {"rx": 8, "chirp": 4, "sample": 32},
         "complex": True},
        {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range",
         "window": "hann"},
        {"id": "ang", "op": "dft", "input": "rng", "axis": "rx", "out_axis": "angle",
         "n_fft": 32, "shift": True},
        {"id": "mag", "op": "magnitude", "input": "ang", "kind": "l2"},
        {"id": "ra", "op": "sum", "input": "mag", "axis": "chirp"},
        {"id": "out", "op": "output", "input": "ra"}]})
    rng = np.random.default_rng(3)
    n = np.arange(32)
    steer = np.exp(1j * np.pi * np.sin(0.4) * np.arange(8))[:, None, None]
    x = 20 * steer * np.exp(2j * np.pi * 6 * n / 32)[None, None, :] + (
        rng.normal(size=(8, 4, 32)) + 1j * rng.normal(size=(8, 4, 32)))
    for target in ("unbounded", "loihi2"):
        p = compile_graph(g, target, motifs={"dft": "resonator"}, calibration_inputs={"adc": x})
        got = run_program(p, {"adc": x}, mode="auto").values["out"]
        want = evaluate(g, {"adc": x})["out"]
        assert got.shape == want.shape == (32, 32)
        assert np.unravel_index(got.argmax(), got.shape) == np.unravel_index(want.argmax(),
                                                                             want.shape)
        assert np.abs(got - want).max() / want.max() < 0.02


def test_errors_name_the_node_and_limit():
    with pytest.raises(CompileError, match="stream_bits=40 is outside 1..30"):
        _compile("unbounded", stream_bits=40)
    with pytest.raises(CompileError, match=r"stream_bits=15 is outside 1\.\.14"):
        _compile("loihi2", stream_bits=15)


def test_resources_beside_the_sft():
    x = _signal()
    res = _compile("loihi2", x=x)
    sft = compile_graph(_graph(keep="positive"), "loihi2", calibration_inputs={"x": x},
                        time_steps=256)
    r_net, s_net = res.networks[0], sft.networks[0]
    # fan-out: B bits × 2 parts × 32 bins per chirp stream, not a (2N × 4K) matrix
    bits = r_net.meta["resonator"]["f"]["stream_bits"]
    assert r_net.n_synapses == bits * 2 * (N // 2)
    assert r_net.n_synapses < s_net.n_synapses / 10
    rows = {r["node"]: r for r in build_report(res).data["stages"]}
    assert rows["f"]["motif"] == "resonator"


def test_artifact_round_trip_keeps_the_resonator(tmp_path):
    x = _signal()
    net = _compile("loihi2", x=x).networks[0]
    save(net, tmp_path / "a")
    back = load(tmp_path / "a")
    assert type(back.population["f/out"].params).__name__ == "ResonatorParams"
    a = simulate(net, {"x": x}, mode="closed")
    b = simulate(back, {"x": x}, mode="closed")
    np.testing.assert_array_equal(a.outputs["f"], b.outputs["f"])


def test_emit_and_nir_refuse_resonators_by_name(tmp_path):
    from backends.emit.numpy_emitter import emit_numpy
    from backends.nir import export_network
    from ir.errors import ArtifactError

    net = _compile("unbounded").networks[0]
    with pytest.raises(CompileError, match="population 'f/out'.*no resonator update"):
        emit_numpy(net, tmp_path / "pkg")
    with pytest.raises(ArtifactError, match="population 'f/out'.*resonate-and-fire"):
        export_network(net)
