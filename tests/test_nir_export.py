"""NIR export (backends.nir): node mapping, the export report, write/read round trip through the
real ``nir`` package, and exactness — a small discrete-time NIR interpreter written here from
the NIR node equations reproduces every spike of our step simulator on an exported network."""

from __future__ import annotations

import json

import networkx as nx
import nir
import numpy as np
import pytest

from backends.nir import export_network, export_program, write_nir
from backends.reference import simulate
from backends.reference.encoding import encode_inputs
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
from ir.errors import ArtifactError


def _const(bias: float = 0.0) -> tuple[Phase, ...]:
    return (Phase(start_step=0, bias=bias),)


def _zoo(n_steps: int = 24) -> SpikingNetwork:
    """Every expressible neuron form, delays, recurrence, a stencil, shared weights."""
    rng = np.random.default_rng(0)
    pops = [
        Population(id="x/in", shape={"rep": 2, "i": 3}, source=True),
        Population(id="a/lif", shape={"rep": 2, "o": 3},  # LIF with bias as v_leak
                   params=NeuronParams(du=1.0, dv=0.25, v_th=1.0, reset="value",
                                       phases=_const(0.0625))),
        Population(id="b/cuba", shape={"rep": 2, "o": 3},  # CubaLIF
                   params=NeuronParams(du=0.5, dv=0.5, v_th=0.75, reset="value",
                                       v_reset=-0.25)),
        Population(id="c/ramp", shape={"o": 3, "rep": 2},  # I -> IF, transposed axes
                   params=NeuronParams(du=0.0, dv=0.0, v_th=4.0, reset="value")),
        Population(id="d/li", shape={"rep": 2, "o": 3},  # LI -> IF
                   params=NeuronParams(du=0.25, dv=0.0, v_th=1.5, reset="value")),
        Population(id="e/if", shape={"rep": 2, "o": 3},  # IF with bias on an Affine
                   params=NeuronParams(du=1.0, dv=0.0, v_th=2.0, reset="value",
                                       phases=_const(0.125))),
    ]
    def w(shape):
        return rng.integers(-4, 9, size=shape) / 4.0

    def mp(pid, src, tgt, shape, contract=("i",), delays=None):
        return MatrixProjection(id=pid, source=src, target=tgt, contract=contract,
                                produce=("o",), weights=w(shape), delays=delays)
    projections = [
        mp("a/w", "x/in", "a/lif", (3, 3), delays=rng.integers(0, 3, size=(3, 3))),
        mp("b/w", "a/lif", "b/cuba", (3, 3), contract=("o",)),
        mp("c/w", "x/in", "c/ramp", (3, 3)),
        mp("d/w", "b/cuba", "d/li", (3, 3), contract=("o",)),
        mp("e/w", "x/in", "e/if", (3, 3)),
        mp("e/rec", "e/if", "e/if", (3, 3), contract=("o",), delays=np.ones((3, 3), int)),
        StencilProjection(id="d/k", source="a/lif", target="d/li", axes=("o",),
                          kernel=np.array([0.5, -0.25, 1.0]), edge=("wrap",)),
    ]
    return SpikingNetwork(
        name="zoo", n_steps=n_steps, populations=pops, projections=projections,
        encoders=[Encoder(port="x", population="x/in", code=RateCode(max_rate=0.75))],
        decoders=[Decoder(port="y", population="d/li", kind="count")])


# ------------------------------------------------------------ a NIR interpreter (test oracle)
def run_nir(graph: nir.NIRGraph, inputs: dict[str, np.ndarray], n_steps: int, dt: float
            ) -> dict[str, np.ndarray]:
    """Forward-Euler interpretation of a NIR graph: ``(n_steps, size)`` outputs per node."""
    nodes, edges = graph.nodes, graph.edges
    preds = {k: [a for a, b in edges if b == k] for k in nodes}
    dag = nx.DiGraph([(a, b) for a, b in edges if not isinstance(nodes[a], nir.Delay)])
    dag.add_nodes_from(nodes)
    order = list(nx.lexicographical_topological_sort(dag))
    out = {k: np.zeros((n_steps, int(np.prod(_shape(nodes[k]))))) for k in nodes}
    state = {k: [0.0, 0.0] for k in nodes}
    delays = {k: int(round(n.delay[0] / dt)) for k, n in nodes.items() if isinstance(n, nir.Delay)}
    for t in range(n_steps):
        for k, lag in delays.items():  # delay >= 1 step: reads the past only
            out[k][t] = sum(out[p][t - lag] for p in preds[k]) if t >= lag else 0.0
        for k in order:
            node = nodes[k]
            if isinstance(node, nir.Input):
                out[k][t] = inputs[k][t]
                continue
            if isinstance(node, nir.Delay):
                continue
            x = sum(out[p][t] for p in preds[k]) if preds[k] else np.zeros(out[k].shape[1])
            s = state[k]
            if isinstance(node, nir.Output):
                out[k][t] = x
            elif isinstance(node, nir.Linear):
                out[k][t] = node.weight @ x
            elif isinstance(node, nir.Affine):
                out[k][t] = node.weight @ x + node.bias
            elif isinstance(node, nir.I):
                s[0] = s[0] + dt * node.r * x
                out[k][t] = s[0]
            elif isinstance(node, nir.LI):
                s[0] = s[0] + dt / node.tau * (node.v_leak - s[0] + node.r * x)
                out[k][t] = s[0]
            else:
                if isinstance(node, nir.CubaLIF):
                    s[1] = s[1] + dt / node.tau_syn * (-s[1] + node.w_in * x)
                    s[0] = s[0] + dt / node.tau_mem * (node.v_leak - s[0] + node.r * s[1])
                elif isinstance(node, nir.LIF):
                    s[0] = s[0] + dt / node.tau * (node.v_leak - s[0] + node.r * x)
                else:  # IF
                    s[0] = s[0] + dt * node.r * x
                z = s[0] > node.v_threshold
                s[0] = np.where(z, node.v_reset, s[0])
                out[k][t] = z
    return out


def _shape(node: nir.NIRNode) -> np.ndarray:
    return node.output_type["output"]


def _input_rasters(net: SpikingNetwork, inputs: dict) -> dict[str, np.ndarray]:
    trains, _, _ = encode_inputs(net, inputs)
    rasters = {}
    for pid, train in trains.items():
        flat, steps = train.all_events()
        r = np.zeros((net.n_steps, net.population[pid].size))
        r[steps, flat] = 1.0
        rasters[pid.replace("/", ".")] = r
    return rasters


# ------------------------------------------------------------------------------ tests
def test_node_types_names_and_report() -> None:
    graph, report = export_network(_zoo())
    kinds = {k: type(v).__name__ for k, v in graph.nodes.items()}
    assert kinds["x.in"] == "Input" and kinds["y.output"] == "Output"
    assert (kinds["a.lif"], kinds["b.cuba"], kinds["c.ramp"], kinds["c.ramp.syn"]) == (
        "LIF", "CubaLIF", "IF", "I")
    assert (kinds["d.li.syn"], kinds["d.li"], kinds["e.w.d0"]) == ("LI", "IF", "Affine")
    assert kinds["e.rec.delay1"] == "Delay" and kinds["e.rec.d1"] == "Linear"
    assert report.is_exact  # only the encoder and decoder run outside
    assert {e.aspect for e in report.outside} == {"encoder", "decoder"}
    assert report.nodes["e.rec.d1"] == "e/rec"
    assert graph.nodes["a.lif"].metadata["radarsnn_node"] == "a"
    # hand-worked LIF mapping: dv = 1/4 -> tau = 4 dt, r = 4, v_leak = b/dv = 1/4
    a = graph.nodes["a.lif"]
    assert (a.tau[0], a.r[0], a.v_leak[0]) == (4.0, 4.0, 0.25)
    assert a.v_threshold[0] == np.nextafter(1.0, 0.0) and a.v_threshold[0] < 1.0


def test_exported_graph_reproduces_every_spike(tmp_path) -> None:
    net = _zoo()
    x = np.random.default_rng(5).uniform(0, 1, size=(2, 3))
    ours = simulate(net, {"x": x}, mode="step", record_spikes=True)
    graph, report = export_network(net)
    write_nir(graph, report, tmp_path / "zoo.nir")
    back = nir.read(tmp_path / "zoo.nir")
    got = run_nir(back, _input_rasters(net, {"x": x}), net.n_steps, dt=1.0)
    for pop in net.populations:
        if not pop.source:
            want = ours.spikes[pop.id][0].reshape(net.n_steps, -1)
            np.testing.assert_array_equal(got[pop.id.replace("/", ".")], want, err_msg=pop.id)
            assert want.any(), pop.id  # every population fires
    np.testing.assert_array_equal(got["y.output"].sum(0), ours.outputs["y"].ravel())


def test_round_trip_through_nir_write_read(tmp_path) -> None:
    graph, report = export_network(_zoo(), dt_s=1e-3)
    write_nir(graph, report, tmp_path / "zoo.nir")
    back = nir.read(tmp_path / "zoo.nir")
    assert set(back.nodes) == set(graph.nodes)
    assert sorted(map(tuple, back.edges)) == sorted(graph.edges)
    for name, node in graph.nodes.items():
        other = back.nodes[name]
        assert type(other) is type(node), name
        for field in ("weight", "bias", "tau", "r", "v_leak", "v_threshold", "v_reset",
                      "tau_syn", "tau_mem", "w_in", "delay"):
            if hasattr(node, field):
                np.testing.assert_array_equal(getattr(other, field), getattr(node, field))
    meta = back.nodes["a.lif"].metadata
    params = json.loads(meta["radarsnn_params"].decode() if isinstance(
        meta["radarsnn_params"], bytes) else meta["radarsnn_params"])
    assert params["dv"] == 0.25 and params["reset"] == "value"
    assert np.isclose(back.nodes["e.rec.delay1"].delay[0], 1e-3)
    saved = json.loads((tmp_path / "zoo.report.json").read_text())
    assert saved["path"].endswith("zoo.nir") and saved["counts"]["outside"] == 2


def test_unexpressible_behaviour_is_listed_not_dropped() -> None:
    """The S-FT neuron: silent/charging phases and fire-once are reported ``outside``."""
    sft = NeuronParams(du=0.0, dv=0.0, v_th=10.0, reset="fire_once",
                       phases=(Phase(start_step=0, spiking_on=False),
                               Phase(start_step=4, bias=1.0, input_on=False)))
    net = SpikingNetwork(
        name="ramp", n_steps=8,
        populations=[Population(id="f/in", shape={"i": 2}, source=True),
                     Population(id="f/out", shape={"o": 1}, params=sft),
                     Population(id="g/sub", shape={"o": 1},
                                params=NeuronParams(du=0.5, v_th=1.0, reset="subtract",
                                                    phases=_const(0.5)))],
        projections=[MatrixProjection(id="f/w", source="f/in", target="f/out", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1))),
                     MatrixProjection(id="g/w", source="f/out", target="g/sub",
                                      contract=("o",), produce=("o",), weights=np.ones((1, 1)))],
        encoders=[Encoder(port="x", population="f/in",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="f/out", kind="spike_time")])
    _, report = export_network(net)
    outside = {(e.item, e.aspect) for e in report.outside}
    assert {("f/out", "schedule"), ("f/out", "reset"), ("g/sub", "reset"), ("g/sub", "bias"),
            ("f/in", "encoder"), ("t", "decoder")} == outside
    assert not report.is_exact
    assert "fire-once" in report.summary()


def test_program_export_names_trace_to_ir_nodes() -> None:
    from compiler.compile import compile_graph
    from ir import Graph

    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 12}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "x", "kind": "ca", "guard": 1, "train": 2,
         "alpha": 2.0},
        {"id": "o", "op": "output", "input": "det"}]})
    program = compile_graph(g, target=None, calibration_inputs={"x": np.arange(1.0, 13.0)},
                            time_steps=32)
    graph, report = export_program(program, stages=["det"])
    origins = {graph.nodes[k].metadata.get("radarsnn_node") for k in graph.nodes
               if "radarsnn_node" in graph.nodes[k].metadata}
    assert origins == {"det", "x"}  # the encoder reads IR node x
    assert all(k.startswith("det.") for k in graph.nodes)
    with pytest.raises(ArtifactError, match="no spiking network"):
        export_program(program, stages=["nope"])


def test_over_max_weights_a_projection_is_one_compact_node() -> None:
    """No dense blow-up: the shared block of a repeated matrix as one Linear, a stencil as an
    empty Linear with its kernel in metadata; both reported outside NIR."""
    graph, report = export_network(_zoo(), max_weights=9)
    shared = graph.nodes["c.w.compact"]  # 3 x 3 shared by 2 repetitions (6 x 6 dense)
    np.testing.assert_array_equal(shared.weight, _zoo().projection["c/w"].weights.T)
    assert shared.metadata["radarsnn_weight_field"] == "weights"
    stencil = graph.nodes["d.k.compact"]
    assert stencil.weight.shape == (0, 0)
    np.testing.assert_array_equal(stencil.metadata["radarsnn_array_kernel"], [0.5, -0.25, 1.0])
    outside = {e.item for e in report.outside if e.aspect == "weights"}
    assert {"c/w", "d/k"} <= outside and not report.is_exact
    assert ("x.in", "c.w.compact") in graph.edges and ("c.w.compact", "c.ramp.syn") in graph.edges
    # e/if's constant bias rides on an Affine only when its projection is written dense
    assert type(graph.nodes["e.w.compact"]).__name__ == "Linear"
    assert ("e/if", "bias", "outside") in {(e.item, e.aspect, e.kind) for e in report.entries}


def test_errors_name_the_projection() -> None:
    with pytest.raises(ArtifactError, match="dt_s"):
        export_network(_zoo(), dt_s=0.0)
