"""Float forward pass, plan matrices, lowering == forward, quantized agreement, report row."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference import simulate
from compiler.classifier import build_layer_plan, classify, load_weights, save_weights
from compiler.classifier.default import ROI_SHAPE, default_classifier
from compiler.compile import compile_graph
from compiler.report.classifier import classifier_row
from ir import Graph
from ir.classifier_forward.layers import conv_matrix
from ir.errors import CompileError, IRError
from ir.interpreter import evaluate
from ir.ops.classify import (
    LIF,
    Classifier,
    Conv2d,
    Dense,
    Integrator,
    LevelsEncoding,
    Pool,
    Recurrent,
)


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 3), st.integers(1, 3), st.integers(1, 3), st.integers(1, 3),
       st.integers(3, 7), st.integers(3, 7), st.integers(1, 2), st.integers(1, 2),
       st.integers(0, 1), st.integers(0, 2**31))
def test_conv_matrix_is_a_padded_strided_correlation(ci, co, kh, kw, h, w, sh, sw, p, seed):
    rng = np.random.default_rng(seed)
    k = rng.normal(size=(co, ci, kh, kw))
    x = rng.normal(size=(ci, h, w))
    m, (c, oh, ow) = conv_matrix(k, (ci, h, w), (sh, sw), (p, p))
    xp = np.pad(x, ((0, 0), (p, p), (p, p)))
    direct = np.array([[[np.sum(k[o] * xp[:, i * sh:i * sh + kh, j * sw:j * sw + kw])
                         for j in range(ow)] for i in range(oh)] for o in range(co)])
    assert np.allclose(x.ravel() @ m, direct.ravel())


def test_lif_trace_by_hand() -> None:
    # one input pixel above the level every frame; dense weight 0.6 into a LIF (dv = 0.5):
    # v: 0.6 | 0.3 + 0.6 = 0.9 | 0.45 + 0.6 = 1.05 -> spike, subtract -> 0.05 | 0.025 + 0.6
    op = Classifier(num_classes=2, weights="w", time_axis="t",
                    encoding=LevelsEncoding(levels=(0.0,)),
                    layers=(Dense(units=1, neuron=LIF(dv=0.5)), Integrator(units=2)))
    w = {"layers.0.weight": np.array([[0.6]]), "layers.1.weight": np.array([[1.0], [0.0]])}
    r = classify(op, w, np.ones((1, 4, 1, 1)))
    assert r.spikes.tolist() == [[1, 0]] and r.input_spikes.tolist() == [4]
    assert r.scores.tolist() == [[1.0, 0.0]]  # the integrator counts the one spike
    assert r.synaptic_events.tolist() == [4 + 1]  # 4 inputs x 1 synapse, 1 spike x 1 (w != 0)


TINY = Classifier(num_classes=3, weights="w.npz", encoding=LevelsEncoding(levels=(1.0,)),
                  layers=(Conv2d(channels=3, kernel=(3, 3), stride=(2, 2), padding=(1, 1),
                                 neuron=LIF(dv=0.25)),
                          Pool(mode="max", size=(2, 2)),
                          Recurrent(units=5, neuron=LIF(dv=0.125, reset="value")),
                          Integrator(units=3, dv=0.5)))


def _chain(op: Classifier, shape: dict) -> Graph:
    return Graph.from_dict({"name": "clf", "nodes": [
        {"id": "roi", "op": "input", "shape": shape, "domain": "db"},
        {"id": "cls", "op": "classifier", "input": "roi", **op.params()},
        {"id": "out", "op": "output", "input": "cls"}]})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lowered_network_equals_the_float_forward_pass(tmp_path, seed: int) -> None:
    rng = np.random.default_rng(seed)
    path = tmp_path / "w.npz"
    # dyadic weights: every membrane sum is exact, so the match is exact
    w = {k: np.round(rng.normal(0, 0.7, s) * 8) / 8
         for k, s in TINY.weight_shapes("c", (8, 6)).items()}
    save_weights(path, w)
    op = TINY.model_copy(update={"weights": str(path)})
    g = _chain(op, {"object": 7, "frame": 5, "doppler": 6, "range": 8})
    x = rng.normal(1.0, 1.5, (7, 5, 6, 8))
    ref = classify(op, w, np.swapaxes(x, 2, 3))
    assert np.array_equal(evaluate(g, {"roi": x})["out"], ref.scores)
    net = next(s.network for s in compile_graph(g, target=None).segments if s.kind == "spiking")
    sim = simulate(net, {"roi": x}, mode="step")
    assert np.array_equal(sim.outputs["cls"], ref.scores)
    inner = sum(sim.spike_counts[f"cls/l{i}"] for i in (0, 1, 2))
    assert inner == ref.spikes.sum()
    assert sim.spike_counts["cls/input"] == ref.input_spikes.sum()
    # the forward pass counts the simulator's synaptic events; the delay line that brings
    # frame f in at step f adds one event per input spike
    events = dict(sim.synaptic_events)
    assert events.pop("cls/frames") == ref.input_spikes.sum()
    assert sum(events.values()) == ref.synaptic_events.sum()
    assert len(set(ref.predictions.tolist())) > 1 or seed != 0


def test_shipped_weights_compile_to_8_bits_agree_and_meet_the_events_budget() -> None:
    from compiler.classifier.train import mac_counts
    from radar.roi_dataset import make_dataset

    op = default_classifier()
    ds = make_dataset(16, seed=99, roi_shape=ROI_SHAPE)  # ~30 sequences, not the test split
    ref = classify(op, load_weights(op, ROI_SHAPE), ds.x)
    g = _chain(op, {"frame": 8, "doppler": ROI_SHAPE[1], "range": ROI_SHAPE[0]})
    program = compile_graph(g, target="loihi2")  # loihi: no subtractive reset (below)
    net = next(s.network for s in program.segments if s.kind == "spiking")
    # every stored weight is an 8-bit mantissa times its projection's exponent
    (record,) = program.records["quantize"]
    for p in net.projections:
        if p.values is not None:
            m = p.values / 2.0 ** record.projections[p.id]["exponent"]
            assert np.abs(m).max() <= 127 and np.all(m == np.rint(m)), p.id
    # trained for 8 bits: the shipped weights lie on the quantize pass's grid (float32 file)
    errors = record.projections
    assert max(e["max_rel_error"] for e in errors.values()) < 1e-5
    # a one-step threshold encoder: no input is ever out of its range, under any policy
    sim = simulate(net, {"roi": np.swapaxes(ds.x, 2, 3)}, mode="step", arithmetic="int64",
                   out_of_range="reject")
    pred = np.argmax(sim.outputs["cls"], axis=-1)
    assert np.mean(pred == ref.predictions) >= 0.9  # the benchmark: >= 98 % on the test split
    assert np.mean(ref.predictions == ds.y) >= 0.8
    # every synaptic event the simulator counts (the input delay line included) per sequence
    per_sequence = sum(sim.synaptic_events.values()) / len(ds.y)
    assert per_sequence <= 0.01 * mac_counts(ROI_SHAPE, 8)["ann"]


def test_real_encoding_and_many_levels_have_no_spiking_form(tmp_path) -> None:
    shape = {"frame": 2, "doppler": 4, "range": 4}
    for enc in ({"kind": "real"}, {"kind": "levels", "levels": [1.0, 2.0]}):
        op = Classifier(num_classes=2, weights=str(tmp_path / "w.npz"), encoding=enc,
                        layers=(Integrator(units=2),))
        with pytest.raises(CompileError, match=r"node 'cls' \(classifier\): encoding"):
            compile_graph(_chain(op, shape), target=None)
        prog = compile_graph(_chain(op, shape), target=None, motifs={"cls": "host"})
        assert [s.kind for s in prog.segments] == ["host", "host"]


def test_missing_weights_file_is_an_irerror(tmp_path) -> None:
    op = TINY.model_copy(update={"weights": str(tmp_path / "nope.npz")})
    g = _chain(op, {"frame": 2, "doppler": 6, "range": 8})
    with pytest.raises(IRError, match=r"node 'cls' \(classifier\): cannot read weights"):
        evaluate(g, {"roi": np.zeros((2, 6, 8))})


def test_table3_row_by_hand(tmp_path) -> None:
    w = {k: np.ones(s) for k, s in TINY.weight_shapes("c", (8, 6)).items()}
    save_weights(tmp_path / "w.npz", w)
    op = TINY.model_copy(update={"weights": str(tmp_path / "w.npz")})
    net = next(s.network for s in compile_graph(
        _chain(op, {"object": 2, "frame": 4, "doppler": 6, "range": 8}), target=None).segments
        if s.kind == "spiking")
    row = classifier_row(net, "cls", frames=4)
    # inputs 8 x 6; neurons 3 x 4 x 3 conv + 3 x 2 x 1 pool + 5 + 3 = 50
    assert (row.inputs, row.neurons, row.steps_per_frame) == (48, 50, 1)
    conv = build_layer_plan(op, w, (8, 6))
    expect = sum(p.matrix.nnz for p in conv) + 25
    assert row.synapses == expect
