"""Generated numpy simulators reproduce backends.reference step mode exactly, motif by motif.

Each test compiles (or builds) a small network, emits its package, runs it in a fresh
interpreter (``python -m <package>``) and compares outputs and spike counts bit for bit
with ``run_program(..., mode="step")`` / ``simulate(..., mode="step")``.
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.emit import emit_numpy
from backends.emit.numpy_host import emit_host
from backends.emit.package import PackageBuilder
from backends.emit.run_package import run_package
from backends.reference import run_program, simulate
from compiler.classifier import classify, save_weights
from compiler.compile import compile_graph
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
    StencilProjection,
)
from ir import Graph
from ir.errors import CompileError
from ir.ops import Magnitude
from ir.ops.classify import LIF, Classifier, Conv2d, Integrator, LevelsEncoding, Pool, Recurrent
from ir.types import TensorType


def _same(out: dict, want: dict) -> None:
    assert sorted(out) == sorted(want)
    for key in want:
        np.testing.assert_array_equal(out[key], want[key], err_msg=key)


def _check_program(program, inputs, tmp_path) -> list[dict]:
    ref = run_program(program, inputs, mode="step")
    out, counts = run_package(emit_numpy(program, tmp_path), inputs)
    _same(out, ref.outputs)
    assert counts == [s.spike_counts for s in ref.simulations]
    return counts


def _dft_graph(n_chirps: int = 3, n_samples: int = 16) -> Graph:
    return Graph.from_dict({"name": "dft", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": n_chirps, "sample": n_samples}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin"},
        {"id": "m", "op": "magnitude", "input": "f", "kind": "square"},
        {"id": "o", "op": "output", "input": "m"}]})


@pytest.mark.parametrize(("motif", "steps"), [("time", 64), ("time-fft", 64), ("rate", 300)])
def test_dft_motifs_match_the_reference(motif, steps, tmp_path):
    rng = np.random.default_rng(1)
    x = rng.normal(size=(3, 16))
    program = compile_graph(_dft_graph(), None, motifs={"dft": motif},
                            calibration_inputs={"x": x}, time_steps=steps)
    assert program.networks, "the DFT must be lowered to spikes"
    counts = _check_program(program, {"x": rng.normal(size=(3, 16))}, tmp_path)
    assert sum(sum(c.values()) for c in counts) > 0


@pytest.mark.parametrize("params", [
    {"kind": "os", "guard": 1, "train": 3, "k": 4, "alpha": 3.0, "edge": "clip"},
    {"kind": "ca", "guard": [1, 0], "train": [2, 1], "alpha": 2.5, "edge": ["clip", "wrap"]},
])
def test_cfar_motifs_match_the_reference(params, tmp_path):
    shape = {"range": 12} if params["kind"] == "os" else {"range": 10, "doppler": 6}
    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": shape, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "x", **params},
        {"id": "o", "op": "output", "input": "det"}]})
    rng = np.random.default_rng(2)
    cal = rng.exponential(size=tuple(shape.values()))
    cal.flat[3] = 40.0  # the calibration covers the strong cell (inside the code's range)
    program = compile_graph(g, None, calibration_inputs={"x": cal})
    assert [s.kind for s in program.segments][0] == "spiking"
    x = rng.exponential(size=tuple(shape.values()))
    x.flat[3] = 30.0
    _check_program(program, {"x": x}, tmp_path)


def test_every_host_op_matches_the_interpreter(tmp_path):
    g = Graph.from_dict({"name": "host", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": 8}, "complex": True},
        {"id": "w", "op": "window", "input": "x", "axis": "sample", "kind": "hann"},
        {"id": "f", "op": "dft", "input": "w", "axis": "sample", "out_axis": "bin",
         "keep": "all", "shift": True, "window": "hamming"},
        {"id": "l", "op": "linear", "input": "f", "axis": "chirp",
         "matrix": [[1.0, 0.5, 0.0, -1.0], [0.25, 0.0, 2.0, 1.0]],
         "matrix_imag": [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, -0.5, 0.0]]},
        {"id": "m", "op": "magnitude", "input": "l", "kind": "l1"},
        {"id": "s", "op": "sum", "input": "m", "axis": "chirp"},
        {"id": "db", "op": "log", "input": "s"},
        {"id": "c", "op": "cfar", "input": "s", "kind": "os", "guard": 0, "train": 2, "k": 2,
         "alpha": 1.5, "edge": "wrap"},
        {"id": "t", "op": "threshold", "input": "db", "value": 3.0, "strict": False},
        {"id": "o1", "op": "output", "input": "c"},
        {"id": "o2", "op": "output", "input": "t"},
        {"id": "o3", "op": "output", "input": "db"}]})
    motifs = {op: "host" for op in ("window", "dft", "linear", "magnitude", "sum", "log",
                                     "cfar", "threshold")}
    rng = np.random.default_rng(4)
    x = rng.normal(size=(4, 8)) + 1j * rng.normal(size=(4, 8))
    program = compile_graph(g, None, motifs=motifs, calibration_inputs={"x": x})
    assert not program.networks
    _check_program(program, {"x": x}, tmp_path)


def _lif_network(integer: bool) -> SpikingNetwork:
    """A rate-coded input, a LIF layer (subtract reset) and a delayed value-reset layer."""
    rng = np.random.default_rng(5)
    scale = 1.0 if integer else 1 / 64
    w1 = np.round(rng.normal(size=(6, 5)) * 40) * scale
    w2 = np.round(rng.normal(size=(5, 3)) * 40) * scale
    delays = rng.integers(0, 3, size=(5, 3))
    th = 64.0 * scale
    lif = NeuronParams(du=0.5, dv=0.25, v_th=th, reset="subtract")
    out = NeuronParams(du=1.0, dv=1 / 16, v_th=th, reset="value", v_reset=-th / 4 // 1,
                       phases=(Phase(start_step=0, bias=0.0),
                               Phase(start_step=20, bias=4.0 if integer else 0.0625,
                                     input_on=False),
                               Phase(start_step=30, spiking_on=False)))
    return SpikingNetwork(
        name="lif", n_steps=40,
        populations=[Population(id="in", shape={"batch": 2, "i": 6}, source=True),
                     Population(id="hidden", shape={"h": 5, "batch": 2}, params=lif),
                     Population(id="out", shape={"batch": 2, "o": 3}, params=out)],
        projections=[MatrixProjection(id="w1", source="in", target="hidden", contract=("i",),
                                      produce=("h",), weights=w1),
                     MatrixProjection(id="w2", source="hidden", target="out",
                                      contract=("h",), produce=("o",), weights=w2,
                                      delays=delays)],
        encoders=[Encoder(port="x", population="in", code=RateCode(max_rate=0.75, phase=0.25))],
        decoders=[Decoder(port="rate", population="hidden", kind="count", scale=0.5),
                  Decoder(port="v", population="out", kind="membrane", offset=1.0),
                  Decoder(port="first", population="out", kind="spike_time", t_ref=40.0,
                          missing=np.nan)])


@pytest.mark.parametrize("arithmetic", ["float64", "int64"])
def test_hand_built_lif_layers_match_the_reference(arithmetic, tmp_path):
    net = _lif_network(arithmetic == "int64")
    x = np.random.default_rng(6).uniform(size=(3, 2, 6))  # three frames
    ref = simulate(net, {"x": x}, mode="step", arithmetic=arithmetic)
    out, counts = run_package(emit_numpy(net, tmp_path, arithmetic=arithmetic), {"x": x})
    _same(out, ref.outputs)
    assert counts == [ref.spike_counts]
    assert ref.spike_counts["out"] > 0 and ref.spike_counts["hidden"] > 0


def test_stencil_with_delays_and_latency_log_code(tmp_path):
    kernel = np.array([[0.5, -1.0, 0.25], [1.0, 0.0, 1.0], [0.125, 2.0, -0.5]])
    net = SpikingNetwork(
        name="stencil", n_steps=24,
        populations=[Population(id="a", shape={"r": 7, "d": 5}, source=True),
                     Population(id="b", shape={"d": 5, "r": 7},
                                params=NeuronParams(du=0.0, v_th=3.0, reset="fire_once"))],
        projections=[StencilProjection(id="k", source="a", target="b", axes=("r", "d"),
                                       kernel=kernel, edge=("clip", "wrap"),
                                       delays=np.array([[0, 1, 2], [0, 0, 0], [3, 1, 0]]))],
        encoders=[Encoder(port="x", population="a", normalize_axes=("d",),
                          code=LatencyCode(kind="log", t_max=16, x_min=0.01, x_max=1.0))],
        decoders=[Decoder(port="y", population="b", kind="spike_table", t_ref=2,
                          table=tuple(np.linspace(1.0, 0.0, 12)), missing=-1.0),
                  Decoder(port="s", population="b", kind="spiked")])
    x = np.random.default_rng(7).uniform(0.0, 3.0, size=(7, 5))
    ref = simulate(net, {"x": x}, mode="step")
    out, counts = run_package(emit_numpy(net, tmp_path), {"x": x})
    _same(out, ref.outputs)
    assert counts == [ref.spike_counts]


def test_classifier_motif_matches_the_reference(tmp_path):
    """Conv (stride 2, padding 1) → max pool → recurrent LIF (value reset) → integrator,
    one step per frame, frames arriving through delayed relays (motif ``snn``)."""
    op = Classifier(num_classes=3, weights=str(tmp_path / "w.npz"),
                    encoding=LevelsEncoding(levels=(1.0,)),
                    layers=(Conv2d(channels=3, kernel=(3, 3), stride=(2, 2), padding=(1, 1),
                                   neuron=LIF(dv=0.25)),
                            Pool(mode="max", size=(2, 2)),
                            Recurrent(units=5, neuron=LIF(dv=0.125, reset="value")),
                            Integrator(units=3, dv=0.5)))
    rng = np.random.default_rng(8)
    w = {k: np.round(rng.normal(0, 0.7, s) * 8) / 8  # dyadic: exact sums
         for k, s in op.weight_shapes("c", (8, 6)).items()}
    save_weights(tmp_path / "w.npz", w)
    g = Graph.from_dict({"name": "clf", "nodes": [
        {"id": "roi", "op": "input", "shape": {"object": 3, "frame": 5, "doppler": 6,
                                               "range": 8}, "domain": "db"},
        {"id": "cls", "op": "classifier", "input": "roi", **op.params()},
        {"id": "out", "op": "output", "input": "cls"}]})
    program = compile_graph(g, None)
    assert [s.kind for s in program.segments] == ["spiking", "host"]
    x = rng.uniform(0.0, 2.0, size=(3, 5, 6, 8))  # inside the code's range [0, 2]
    counts = _check_program(program, {"roi": x}, tmp_path / "pkg")
    assert all(counts[0][f"cls/l{i}"] > 0 for i in range(3))
    ref = classify(op, w, np.swapaxes(x, 2, 3))  # (and the spiking network is the model)
    assert counts[0]["cls/input"] == ref.input_spikes.sum()


def test_an_op_without_host_emitter_is_refused_naming_the_node():
    t = TensorType(axes={"range": 4}, complex=True)
    with pytest.raises(CompileError, match="node 'mag-1'.*no numpy host emitter"):
        emit_host(PackageBuilder(), "mag-1", Magnitude(), t, emitters={})
