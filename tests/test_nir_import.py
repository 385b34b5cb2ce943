"""NIR import (backends.nir.importer): an snnTorch-style NIR graph → ``classifier`` op + npz.

The graph is written and read with the real ``nir`` package; the mapping of every
layer, the folded gains and thresholds are checked by hand; errors name the NIR node;
and, once the classifier lowering (issue #8) is registered, the imported op compiles
and simulates like our own classifiers.
"""

from __future__ import annotations

import nir
import numpy as np
import pytest

from backends.nir.importer import import_classifier
from ir import Graph
from ir.errors import IRError

DT = 1e-3


def _snn_graph(conv_bias: float = 0.0, tau_mem=None) -> nir.NIRGraph:
    """Input (1,6,6) → Conv2d+LIF → SumPool2d → Flatten → Linear+CubaLIF (recurrent) → LI."""
    rng = np.random.default_rng(0)
    conv_w = rng.integers(-2, 3, size=(2, 1, 3, 3)).astype(float)
    nodes = {
        "input": nir.Input(input_type=np.array([1, 6, 6])),
        "conv": nir.Conv2d(input_shape=(6, 6), weight=conv_w, stride=1, padding=1, dilation=1,
                           groups=1, bias=np.full(2, conv_bias)),
        "lif1": nir.LIF(tau=np.full((2, 6, 6), 4 * DT), r=np.full((2, 6, 6), 4.0),
                        v_leak=np.zeros((2, 6, 6)), v_threshold=np.full((2, 6, 6), 1.0),
                        v_reset=np.zeros((2, 6, 6))),
        "pool": nir.SumPool2d(kernel_size=np.array([2, 2]), stride=np.array([2, 2]),
                              padding=np.array([0, 0])),
        "flat": nir.Flatten(start_dim=0, end_dim=-1, input_type={"input": np.array([2, 3, 3])}),
        "fc": nir.Linear(weight=np.full((4, 18), 0.5)),
        "rlif": nir.CubaLIF(tau_syn=np.full(4, 2 * DT), tau_mem=tau_mem if tau_mem is not None
                            else np.full(4, 2 * DT), r=np.full(4, 2.0), v_leak=np.zeros(4),
                            v_threshold=np.full(4, 0.5), v_reset=np.zeros(4),
                            w_in=np.full(4, 2.0)),
        "rec": nir.Linear(weight=-np.eye(4)),
        "out_fc": nir.Linear(weight=np.arange(12.0).reshape(3, 4)),
        "li": nir.LI(tau=np.full(3, 8 * DT), r=np.full(3, 8.0), v_leak=np.zeros(3)),
        "output": nir.Output(output_type=np.array([3])),
    }
    edges = [("input", "conv"), ("conv", "lif1"), ("lif1", "pool"), ("pool", "flat"),
             ("flat", "fc"), ("fc", "rlif"), ("rlif", "rec"), ("rec", "rlif"),
             ("rlif", "out_fc"), ("out_fc", "li"), ("li", "output")]
    return nir.NIRGraph(nodes=nodes, edges=edges, metadata={"radarsnn_dt_s": DT})


@pytest.fixture()
def imported(tmp_path):
    nir.write(tmp_path / "snn.nir", _snn_graph())
    op = import_classifier(tmp_path / "snn.nir", tmp_path / "snn.npz", time_axis="frame")
    with np.load(tmp_path / "snn.npz", allow_pickle=False) as f:
        arrays = dict(f)
    return op, arrays


def test_layers_and_folded_gains(imported) -> None:
    op, w = imported
    assert [layer.kind for layer in op.layers] == ["conv2d", "pool", "recurrent", "integrator"]
    conv, pool, rec, out = op.layers
    # LIF tau = 4 dt, r = 4: d_v = 1/4, gain r·dt/tau = 1; threshold v > 1 → v >= next(1)
    assert (conv.neuron.du, conv.neuron.dv, conv.neuron.reset) == (1.0, 0.25, "value")
    assert conv.neuron.v_th == np.nextafter(1.0, 2.0)
    assert (conv.channels, conv.kernel, conv.padding, pool.size) == (2, (3, 3), (1, 1), (2, 2))
    # CubaLIF tau_syn = tau_mem = 2 dt, w_in = 2, r = 2: gain = (1/2·2)·(1/2·2) = 1, and the
    # sum pool's 2 x 2 folds in: 0.5 · 4 = 2 per weight; the recurrent weights keep gain 1
    assert (rec.neuron.du, rec.neuron.dv, rec.units) == (0.5, 0.5, 4)
    np.testing.assert_array_equal(w["layers.2.weight"], np.full((4, 18), 2.0))
    np.testing.assert_array_equal(w["layers.2.recurrent"], -np.eye(4))
    # LI tau = 8 dt, r = 8: d_v = 1/8, gain 1
    assert (out.du, out.dv, op.num_classes) == (1.0, 0.125, 3)
    np.testing.assert_array_equal(w["layers.3.weight"], np.arange(12.0).reshape(3, 4))
    assert sorted(w) == ["layers.0.weight", "layers.2.recurrent", "layers.2.weight",
                         "layers.3.weight"]


def test_imported_op_type_checks_in_a_graph(imported) -> None:
    op, _ = imported
    g = Graph.from_dict({"name": "clf", "nodes": [
        {"id": "roi", "op": "input", "shape": {"object": 2, "frame": 5, "range": 6,
                                                "doppler": 6}, "domain": "amplitude"},
        {"id": "cls", **op.model_dump(mode="json"), "input": "roi"},
        {"id": "o", "op": "output", "input": "cls"}]})
    assert g.infer_types()["cls"].axes == {"object": 2, "class": 3}


def test_import_compile_simulate(tmp_path) -> None:
    from backends.reference import run_program
    from compiler.compile import compile_graph
    from ir.interpreter import evaluate

    # spikes from one reference level (a real-valued first layer has no spiking form)
    nir.write(tmp_path / "snn.nir", _snn_graph())
    op = import_classifier(tmp_path / "snn.nir", tmp_path / "snn.npz", time_axis="frame",
                           encoding={"kind": "levels", "levels": [1.0]})
    g = Graph.from_dict({"name": "clf", "nodes": [
        {"id": "roi", "op": "input", "shape": {"object": 2, "frame": 5, "range": 6,
                                                "doppler": 6}, "domain": "amplitude"},
        {"id": "cls", **op.model_dump(mode="json"), "input": "roi"},
        {"id": "o", "op": "output", "input": "cls"}]})
    x = np.random.default_rng(1).uniform(0, 2, size=(2, 5, 6, 6))
    program = compile_graph(g, target=None, calibration_inputs={"roi": x})
    assert program.networks, "the classifier should lower to spikes"
    got = run_program(program, {"roi": x}, mode="step").outputs["o"]
    np.testing.assert_allclose(got, evaluate(g, {"roi": x})["cls"], rtol=1e-9, atol=1e-9)


def test_errors_name_the_nir_node(tmp_path) -> None:
    with pytest.raises(IRError, match="'conv'.*non-zero bias"):
        import_classifier(_snn_graph(conv_bias=0.5), tmp_path / "a.npz")
    with pytest.raises(IRError, match="'rlif'.*tau_mem must be one finite value"):
        import_classifier(_snn_graph(tau_mem=np.array([1.0, 2.0, 2.0, 2.0]) * DT),
                          tmp_path / "b.npz")
    with pytest.raises(IRError, match="channels"):
        import_classifier(_snn_graph(), tmp_path / "c.npz",
                          encoding={"kind": "levels", "levels": [0.5, 1.0]})
    lone = nir.NIRGraph.from_list(nir.Linear(weight=np.ones((2, 2))))
    with pytest.raises(IRError, match="Input shape"):
        import_classifier(lone, tmp_path / "d.npz")


def test_imported_classifier_is_allocated_on_loihi2(tmp_path) -> None:
    from backends.reference import run_program
    from compiler.compile import compile_graph
    from ir.interpreter import evaluate

    nir.write(tmp_path / "snn.nir", _snn_graph())
    op = import_classifier(tmp_path / "snn.nir", tmp_path / "snn.npz", time_axis="frame",
                           encoding={"kind": "levels", "levels": [1.0]})
    g = Graph.from_dict({"name": "clf", "nodes": [
        {"id": "roi", "op": "input", "shape": {"object": 2, "frame": 5, "range": 6,
                                                "doppler": 6}, "domain": "amplitude"},
        {"id": "cls", **op.model_dump(mode="json"), "input": "roi"},
        {"id": "o", "op": "output", "input": "cls"}]})
    x = np.random.default_rng(1).uniform(0, 2, size=(2, 5, 6, 6))
    program = compile_graph(g, "loihi2", calibration_inputs={"roi": x})
    totals = program.records["report"].data["totals"]
    assert totals["cores"] >= 1 and totals["neurons"] > 0  # quantized, split and placed
    got = run_program(program, {"roi": x}, mode="step", out_of_range="clip").outputs["o"]
    # 8-bit weights: the class decisions survive quantization on this input
    assert got.argmax(-1).tolist() == evaluate(g, {"roi": x})["cls"].argmax(-1).tolist()
