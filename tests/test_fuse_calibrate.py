"""fuse-linear (equal to the unfused reference) and calibrate (policies, records, encoder)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.reference import simulate
from compiler.chains import range_doppler_chain
from compiler.compile import default_pipeline
from compiler.passes import CompileContext
from compiler.passes.calibrate import mixed_axes
from compiler.passes.fuse_linear import FuseLinear
from compiler.program import CompiledProgram
from compiler.snn import Decoder, Encoder, LatencyCode, Population, SpikingNetwork
from ir import Graph, evaluate
from ir.errors import CompileError, NetworkError
from radar.config import preset


def fuse(graph: Graph) -> CompiledProgram:
    return FuseLinear().apply(CompileContext(), CompiledProgram(graph=graph))


def calibrate(graph: Graph, calib=None, **options) -> CompiledProgram:
    """The calibrate pass as ``compile_graph`` configures it from ``options``."""
    ctx = CompileContext(calibration_inputs=calib or {})
    (calibrate_pass,) = [p for p in default_pipeline(options) if p.name == "calibrate"]
    return calibrate_pass.apply(ctx, CompiledProgram(graph=graph))


def chain(*nodes: dict, shape=None, complex_in=True) -> Graph:
    shape = shape or {"chirp": 6, "sample": 8}
    body = [{"id": "x", "op": "input", "shape": shape, "complex": complex_in}]
    prev = "x"
    for i, n in enumerate(nodes):
        body.append({"id": f"n{i}", "input": prev, **n})
        prev = f"n{i}"
    body.append({"id": "o", "op": "output", "input": prev})
    return Graph.from_dict({"name": "c", "nodes": body})


def _x(graph: Graph, seed: int) -> np.ndarray:
    t = graph.infer_types()["x"]
    rng = np.random.default_rng(seed)
    x = rng.normal(size=t.shape)
    return x + 1j * rng.normal(size=t.shape) if t.complex else x


def assert_same_values(a: Graph, b: Graph, seed: int) -> None:
    x = _x(a, seed)
    np.testing.assert_allclose(evaluate(b, {"x": x})["o"], evaluate(a, {"x": x})["o"],
                               rtol=1e-10, atol=1e-10)


# ------------------------------------------------------------------ fuse-linear


@given(kind=st.sampled_from(["hann", "hamming", "blackman", "rect"]),
       keep=st.sampled_from(["all", "positive"]), shift=st.booleans(),
       n_fft=st.sampled_from([None, 8, 12]), seed=st.integers(0, 1000))
def test_window_into_dft_equals_unfused(kind, keep, shift, n_fft, seed) -> None:
    g = chain({"op": "window", "axis": "sample", "kind": kind},
              {"op": "dft", "axis": "sample", "keep": keep, "shift": shift, "n_fft": n_fft})
    p = fuse(g)
    assert [p.graph.op(n).op for n in p.graph.topological_order()] == ["input", "dft", "output"]
    assert p.graph.op("n1").window == (None if kind == "rect" else kind)
    assert p.records["fuse-linear"][0] == {"rule": "window-into-dft", "into": "n1",
                                           "folded": "n0", "synapses_before": None,
                                           "synapses_after": None}
    assert_same_values(g, p.graph, seed)


def test_carrada_chain_windows_fold_and_values_agree() -> None:
    g = range_doppler_chain(preset("carrada"))
    d = g.to_dict()
    d["nodes"][0]["shape"] = {"rx": 2, "chirp": 16, "sample": 32}  # small, same structure
    g = Graph.from_dict(d)
    p = fuse(g)
    assert [r["folded"] for r in p.records["fuse-linear"]] == ["win", "dwin"]
    assert p.graph.op("rng").window == "hann" and p.graph.op("dop").window == "hann"
    t = g.infer_types()["adc"]
    adc = np.random.default_rng(3).normal(size=t.shape) * (1 + 1j)
    want, got = evaluate(g, {"adc": adc}), evaluate(p.graph, {"adc": adc})
    np.testing.assert_allclose(got["out"], want["out"])
    np.testing.assert_allclose(got["mag"], want["mag"], rtol=1e-9, atol=1e-6)


def test_window_into_linear_and_diagonal_linear_into_dft() -> None:
    diag = np.diag([1.0, 2.0, 0.5, -1.0]).tolist()
    g = chain({"op": "window", "axis": "sample", "kind": "hamming"},
              {"op": "linear", "axis": "sample", "matrix": diag},
              {"op": "dft", "axis": "sample", "out_axis": "bin"}, shape={"sample": 4})
    p = fuse(g)
    rules = [r["rule"] for r in p.records["fuse-linear"]]
    assert rules == ["window-into-linear", "linear-chain"]
    assert p.records["fuse-linear"][1]["synapses_before"] == 4 + 16
    assert p.records["fuse-linear"][1]["synapses_after"] == 16
    assert [p.graph.op(n).op for n in p.graph.topological_order()] == ["input", "linear", "output"]
    assert p.graph.op("n2").out_axis == "bin"
    assert_same_values(g, p.graph, 1)


def test_dft_of_dft_is_a_permutation_and_fuses() -> None:
    """F·F = N·(k → −k mod N): 8 non-zero weights instead of 2·64."""
    g = chain({"op": "dft", "axis": "sample"}, {"op": "dft", "axis": "sample"})
    p = fuse(g)
    (rec,) = p.records["fuse-linear"]
    assert (rec["rule"], rec["synapses_before"], rec["synapses_after"]) == ("linear-chain", 128, 8)
    assert_same_values(g, p.graph, 2)


def test_bottleneck_chain_is_not_fused() -> None:
    """A 2×8 then an 8×2 map: 32 weights; their product would have 64."""
    rng = np.random.default_rng(0)
    g = chain({"op": "linear", "axis": "sample", "out_axis": "k", "matrix": rng.normal(
        size=(2, 8)).tolist()}, {"op": "linear", "axis": "k", "out_axis": "sample",
                                  "matrix": rng.normal(size=(8, 2)).tolist()})
    p = fuse(g)
    assert p.records["fuse-linear"] == [] and p.graph is g


def test_window_shared_by_two_consumers_stays() -> None:
    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 8}},
        {"id": "w", "op": "window", "input": "x", "axis": "sample"},
        {"id": "f", "op": "dft", "input": "w", "axis": "sample"},
        {"id": "o", "op": "output", "input": "f"},
        {"id": "o2", "op": "output", "input": "w"}]})
    p = fuse(g)
    assert "w" in p.graph and p.graph.inputs_of("f") == ("x",)
    x = np.random.default_rng(0).normal(size=8)
    np.testing.assert_allclose(evaluate(p.graph, {"x": x})["o"], evaluate(g, {"x": x})["o"])


# ------------------------------------------------------------------ calibrate


def test_static_records_hand_worked() -> None:
    """x = [1, 0, −1, 0] → X = [0, 2, 0, 2]; x = [0, 1, 0, 0] → X = [1, −i, −1, i]."""
    g = chain({"op": "dft", "axis": "sample"}, shape={"sample": 4}, complex_in=False)
    rec = calibrate(g, {"x": np.array([[1.0, 0, -1, 0], [0, 1, 0, 0]])}).records["calibrate"]
    f = rec.nodes["n0"]
    assert (rec.policy, rec.source, rec.n_frames, rec.headroom) == ("static", "inputs", 2, 1.0)
    assert (f.max_re, f.max_im, f.max_abs, f.max_l1, f.min, f.max) == (2, 1, 2, 2, -1, 2)
    assert rec.nodes["x"].normalize_axes == () and len(f.part_quantiles) == 257
    assert rec.to_dict()["nodes"]["n0"]["max_re"] == 2


def test_per_input_normalises_each_chirp() -> None:
    g = chain({"op": "dft", "axis": "sample"}, shape={"chirp": 2, "sample": 4}, complex_in=False)
    x = np.array([[1.0, 0, -1, 0], [0, 10, 0, 0]])
    rec = calibrate(g, {"x": x}, calibration="per-input").records["calibrate"]
    assert rec.nodes["x"].normalize_axes == ("sample",)
    assert rec.nodes["x"].max_part == 1.0
    assert rec.nodes["n0"].max_re == 2.0  # chirp 0 → [0, 2, 0, 2]; chirp 1 → [1, −i, −1, i]


def test_mixed_axes_follow_dft_and_sum() -> None:
    g = range_doppler_chain(preset("seed003"))
    assert mixed_axes(g, "adc") == ("rx", "chirp", "sample")
    g1 = chain({"op": "dft", "axis": "sample"})
    assert mixed_axes(g1, "x") == ("sample",)


def test_bounds_propagate_and_errors() -> None:
    g = chain({"op": "window", "axis": "sample", "kind": "rect"}, {"op": "dft", "axis": "sample"},
              shape={"sample": 4}, complex_in=False)
    rec = calibrate(g, input_bounds={"x": 0.5}).records["calibrate"]
    assert rec.source == "bounds" and rec.nodes["n1"].max_part == 4 * 0.5  # Σ_l(|cos|+|sin|)
    assert calibrate(g).records["calibrate"].source == "none"  # nothing to measure: no records
    assert calibrate(g).records["calibrate"].nodes == {}
    with pytest.raises(CompileError, match="not a policy"):
        calibrate(g, calibration="adaptive")
    with pytest.raises(CompileError, match="headroom"):
        calibrate(g, input_bounds={"x": 1.0}, headroom=0.5)
    with pytest.raises(CompileError, match="has shape"):
        calibrate(g, {"x": np.zeros(5)})


# ------------------------------------------------------------------ encoder / decoder extensions


def _net(**enc) -> SpikingNetwork:
    return SpikingNetwork(
        name="n", n_steps=8,
        populations=[Population(id="a", shape={"c": 2, "s": 2}, source=True)],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0), **enc)],
        decoders=[Decoder(port="t", population="a", kind="spike_time", t_ref=8.0,
                          scale=0.125, missing=-1.0)])


def test_encoder_normalize_axes_per_slice() -> None:
    """Per row max 4 and 0.5: [2, 4] → [0.5, 1] (steps 4, 0); [0.5, 0.25] → [1, 0.5]."""
    x = np.array([[2.0, 4.0], [0.5, 0.25]])
    out = simulate(_net(normalize_axes=("s",)), {"x": x}).outputs["t"]
    assert out.tolist() == [[0.5, 1.0], [1.0, 0.5]]
    plain = simulate(_net(), {"x": np.clip(x, 0, 1)}).outputs["t"]
    assert plain.tolist() == [[1.0, 1.0], [0.5, 0.25]]
    with pytest.raises(NetworkError, match="normalize_axes"):
        simulate(_net(normalize_axes=("part",)), {"x": x})


def test_spike_table_decoder() -> None:
    net = SpikingNetwork(name="n", n_steps=8, populations=_net().populations,
                         encoders=_net().encoders, decoders=[Decoder(
                             port="t", population="a", kind="spike_table", t_ref=2.0,
                             table=(9.0, 7.0, 5.0), missing=0.0)])
    # x = 1 − t/8: steps 2, 3, 4 → table 9, 7, 5; step 0 before the table → missing.
    y = simulate(net, {"x": np.array([[0.75, 0.625], [0.5, 1.0]])}).outputs["t"]
    assert y.tolist() == [[9.0, 7.0], [5.0, 0.0]]
    with pytest.raises(ValueError, match="spike_table"):
        Decoder(port="t", population="a", kind="spike_table", t_ref=0.5, table=(1.0,))


def test_fused_node_keeps_its_complex_type() -> None:
    """A zero linear folded into a dft: the product has no imaginary part, yet the dft's output
    (and every other surviving node's type) must not change (found by the compile property)."""
    g = Graph.from_dict({"name": "z", "nodes": [
        {"id": "x", "op": "adc_input", "shape": {"a": 4}},
        {"id": "lin", "op": "linear", "input": "x", "axis": "a", "matrix": [[0.0] * 4]},
        {"id": "f", "op": "dft", "input": "lin", "axis": "a"},
        {"id": "o", "op": "output", "input": "f"}]})
    fused = FuseLinear().apply(CompileContext(), CompiledProgram(graph=g)).graph
    assert fused.op("f").op == "linear"
    before, after = g.infer_types(), fused.infer_types()
    assert all(after[n] == before[n] for n in after)
    x = np.arange(4.0)
    np.testing.assert_array_equal(evaluate(fused, {"x": x})["o"], evaluate(g, {"x": x})["o"])
    assert np.iscomplexobj(evaluate(fused, {"x": x})["o"])
