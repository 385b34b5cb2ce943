"""The ``rate`` motif: two-ReLU rate-coded S-DFT, 1-D and 2-D (range-Doppler) forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from backends.reference import simulate
from compiler.compile import lower_pass, motif_settings
from compiler.lowering import LoweringContext, default_registry, lower_graph
from compiler.lowering.dft_common import modulus_rmse, real_weights
from compiler.lowering.dft_rate import worst_case_bound
from compiler.passes import CompileContext, Verify, run_pipeline
from compiler.passes.calibrate import Calibrate
from compiler.program import CompiledProgram
from ir import Graph
from ir.errors import CompileError
from ir.interpreter import evaluate
from radar.config import preset
from radar.scene import SCENE_PRESETS, simulate_frame


def _graph(n: int, reps: int = 1) -> Graph:
    return Graph.from_dict({"name": "rate", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": reps, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin"},
        {"id": "o", "op": "output", "input": "f"}]})


def _lower(g: Graph, steps: int, **options):
    ctx = LoweringContext(graph=g, registry=default_registry(), motifs={"dft": "rate"},
                          settings=motif_settings({"time_steps": steps, **options}))
    return lower_graph(ctx)


def test_two_point_dft_by_hand():
    # X = 1, input rate 0.5 at X, phase 0.5: x0 = 1 spikes at steps 0, 2, 4, 6; x1 = 0.5 at 1, 5.
    # Worst case Y = 2, v_th = Y / (s_in r_out) = 2 / (2 * 0.5) = 2, v starts at v_th/2 = 1.
    # +Re bin 0 (drive s0 + s1): v = 2 @0 spike, 1, 2 @2 spike, 0, 1, 2 @5 spike, 1, 1 -> 3.
    # +Re bin 1 (drive s0 - s1): 2 @0 spike, -1, 0, 0, 1, 0, 1, 1 -> 1.  Scale Y/r_out/T = 4/8.
    seg = _lower(_graph(2), steps=8)[0]
    r = simulate(seg.network, {"x": np.array([[1.0, 0.5]])})
    counts = r.spike_counts
    assert counts["f/out"] == 4
    assert r.outputs["f"].tolist() == [[1.5 + 0j, 0.5 + 0j]]


@settings(deadline=None, max_examples=25)
@given(arrays(np.float64, 8, elements=st.floats(-1, 1)))
def test_count_decoding_error_is_bounded(x):
    # Regular trains count within 1/2 spike of n·r, so the cumulative drive of part q is within
    # E_q = ½ Σ_j |M_jq| of its mean; a neuron's count then lies within 1 + E_q / v_th of
    # T·drive/v_th, and a ± pair within twice that: |ŷ - y| <= 2 (1 + E/v_th) s_out / T.
    steps = 400
    net = _lower(_graph(8), steps=steps)[0].network
    y = simulate(net, {"x": x[None]}).outputs["f"][0]
    m = real_weights(np.fft.fft(np.eye(8), axis=0), "signed", "re_im_signed")
    v_th = net.population["f/out"].params.v_th
    e = 0.5 * np.abs(m).sum(axis=0).max()
    s_out = worst_case_bound(m, "signed", 1.0) / 0.5
    bound = 2 * (1 + e / v_th) * s_out / steps
    err = y - np.fft.fft(x)
    assert np.abs(err.real).max() <= bound and np.abs(err.imag).max() <= bound


def test_2d_reads_the_range_spikes_directly():
    g = Graph.from_dict({"name": "rd", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 8, "sample": 16}},
        {"id": "rng", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range",
         "keep": "positive", "window": "hann"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler",
         "shift": True},
        {"id": "o", "op": "output", "input": "dop"}]})
    segments = _lower(g, steps=3000, input_range=1.0)
    # one spiking segment, no host boundary between the layers (the output node is on the host)
    assert [(s.kind, s.node) for s in segments] == [("spiking", None), ("host", "o")]
    net = segments[0].network
    assert net.projection["dop/w"].source == "rng/out"
    assert net.population["dop/out"].shape == {"doppler": 8, "range": 8, "part": 4}
    assert [e.port for e in net.encoders] == ["x"] and [d.port for d in net.decoders] == ["dop"]
    x = np.cos(2 * np.pi * (3 * np.arange(16)[None] / 16 + 2 * np.arange(8)[:, None] / 8))
    y = simulate(net, {"x": x}).outputs["dop"]
    ref = evaluate(g, {"x": x})["dop"]
    peak = np.unravel_index(np.abs(ref).argmax(), ref.shape)
    assert np.unravel_index(np.abs(y).argmax(), y.shape) == peak
    assert np.abs(y - ref).max() < 0.02 * np.abs(ref).max()


@pytest.fixture(scope="module")
def seed003_small():
    """4 chirps x 256 samples of the seed003 scene (targets at 5, 9 and 100 m)."""
    frame = simulate_frame(preset("seed003"), SCENE_PRESETS["seed003"](), seed=1)
    return frame.adc[0, :4, :256]


@pytest.mark.parametrize("two_d, limit", [(False, 0.0056), (True, 0.0060)])
def test_seed003_rmse_reduced_size(seed003_small, two_d, limit):
    nodes = [{"id": "adc", "op": "input", "shape": {"chirp": 4, "sample": 256}},
             {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range",
              "keep": "positive", "window": "hann"}]
    if two_d:
        nodes.append({"id": "dop", "op": "dft", "input": "rng", "axis": "chirp",
                      "out_axis": "doppler", "shift": True})
    out = nodes[-1]["id"]
    g = Graph.from_dict({"name": "s", "nodes": [*nodes, {"id": "o", "op": "output",
                                                         "input": out}]})
    x = seed003_small
    ctx = CompileContext(calibration_inputs={"adc": x})
    lower = lower_pass({"motifs": {"dft": "rate"}, "time_steps": 250})
    program = run_pipeline([Verify(), Calibrate(), lower], ctx, CompiledProgram(graph=g))
    (net,) = program.networks
    y = simulate(net, {"adc": x}).outputs[out]
    rmse = modulus_rmse(y, evaluate(g, {"adc": x})[out])
    assert rmse <= limit


def test_short_frames_are_refused():
    with pytest.raises(CompileError, match="time_steps=1"):
        _lower(_graph(4), steps=1)


@pytest.mark.parametrize("motif", ["rate", "time-fft"])
def test_per_input_policy_normalises_each_chirp(motif):
    """``per-input``: the encoder divides each chirp by its largest part at run time, so two
    chirps 100x apart in scale are transformed with the same relative accuracy; the decoded
    values are the DFT of the normalised chirps."""
    from compiler.compile import compile_graph
    from compiler.lowering.dft_common import sft_rmse

    rng = np.random.default_rng(3)
    x = rng.normal(size=(2, 64)) * np.array([[1.0], [100.0]])
    g = Graph.from_dict({"name": "pi", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 64}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin",
         "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})
    steps = 2000 if motif == "rate" else 256
    program = compile_graph(g, None, motifs={"dft": motif}, calibration="per-input",
                            calibration_inputs={"x": x}, time_steps=steps)
    (net,) = program.networks
    assert net.encoders[0].normalize_axes == ("sample",)
    y = simulate(net, {"x": x}).outputs["f"]
    want = np.fft.fft(x / np.abs(x).max(axis=1, keepdims=True), axis=1)[:, :32]
    for chirp in range(2):  # both chirps use the whole code range
        assert sft_rmse(y[chirp], want[chirp]) < 0.03
