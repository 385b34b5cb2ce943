"""NIR round trip (backends.nir.import_nir): every network kind export writes — S-FT, S-FFT,
rate S-DFT, the l1 and amb magnitudes, 1-D and 2-D CFAR (OS and CA, clip and wrap edges), the
classifier, repeated DFTs written compact — is read back equal field for field and runs to the
same bits; a graph from another tool (the NIR subset) runs to the spikes of an independent NIR
interpreter. Resonator networks are refused by the export (test_nir_export.py)."""

from __future__ import annotations

import dataclasses
import json

import nir
import numpy as np
import pytest
from test_nir_export import _input_rasters, _zoo, run_nir

from backends import load, save
from backends.nir import export_network, export_program, import_nir, write_nir
from backends.nir.generic import import_generic
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from ir import Graph
from ir.errors import ArtifactError, IRError

RANGE_CFAR = """name: tiny-range-cfar
nodes:
  - {id: x, op: input, shape: {sample: 32}}
  - {id: rng, op: dft, input: x, axis: sample, out_axis: range, keep: positive}
  - {id: mag, op: magnitude, input: rng, kind: square}
  - {id: det, op: cfar, input: mag, kind: os, guard: 1, train: 2, k: 3, alpha: 4.0}
  - {id: out, op: output, input: det}
"""

RD_CFAR = """name: small-rd-cfar
nodes:
  - {id: adc, op: adc_input, shape: {chirp: 8, sample: 16}, complex: true}
  - {id: rng, op: dft, input: adc, axis: sample, out_axis: range, keep: all}
  - {id: dop, op: dft, input: rng, axis: chirp, out_axis: doppler, shift: true}
  - {id: mag, op: magnitude, input: dop, kind: l2}
  - {id: det, op: cfar, input: mag, kind: CFAR_KIND, axes: [range, doppler], guard: [1, 1],
     train: [2, 1], alpha: 1.5, edge: [clip, wrap]}
  - {id: out, op: output, input: det}
"""


def _same_run(program, inputs: dict, tmp_path, **export) -> list:
    """Export every spiking network, read them back, and run both programs: same bits."""
    graph, report = export_program(program, **export)
    write_nir(graph, report, tmp_path / "p.nir")
    back = iter(import_nir(tmp_path / "p.nir"))
    segments = [dataclasses.replace(s, network=next(back)) if s.kind == "spiking" else s
                for s in program.segments]
    assert next(back, None) is None
    copy = dataclasses.replace(program, segments=segments)
    for old, new in zip(program.segments, segments, strict=True):
        if old.kind == "spiking":
            assert new.network.populations == old.network.populations
            for p, q in zip(old.network.projections, new.network.projections, strict=True):
                assert type(p) is type(q) and p.id == q.id
                for f in dataclasses.fields(p):
                    a, b = getattr(p, f.name), getattr(q, f.name)
                    if isinstance(a, np.ndarray):
                        assert a.dtype == b.dtype and np.array_equal(a, b), (p.id, f.name)
                    else:
                        assert a == b, (p.id, f.name)
            assert new.network.encoders == old.network.encoders
            assert new.network.decoders == old.network.decoders
            assert new.network.n_steps == old.network.n_steps
    want = run_program(program, inputs, record_spikes=True)
    got = run_program(copy, inputs, record_spikes=True)
    for key, value in want.values.items():
        np.testing.assert_array_equal(got.values[key], value, err_msg=key)
    assert got.spike_counts == want.spike_counts and want.spike_counts
    assert got.synaptic_events == want.synaptic_events
    return [graph, report]


@pytest.mark.parametrize("target", ["loihi2", None])
@pytest.mark.parametrize("motif", ["time", "time-fft"])
def test_the_s_ft_s_fft_and_1d_os_cfar_run_to_the_same_bits(tmp_path, target, motif) -> None:
    frames = np.random.default_rng(0).standard_normal((4, 32))
    program = compile_graph(Graph.from_yaml(RANGE_CFAR), target,
                            calibration_inputs={"x": frames}, motifs={"rng": motif})
    _same_run(program, {"x": frames[1]}, tmp_path)


RANGE_MAGNITUDE = RANGE_CFAR.replace("kind: square", "kind: l2").replace(
    "  - {id: det, op: cfar, input: mag, kind: os, guard: 1, train: 2, k: 3, alpha: 4.0}\n",
    "").replace("input: det}", "input: mag}")


@pytest.mark.parametrize("target", ["loihi2", None])
@pytest.mark.parametrize("motifs", [{"rng": "rate"}, {"rng": "time", "mag": "l1"},
                                    {"rng": "time-fft", "mag": "amb"}],
                         ids=["rate", "l1", "amb"])
def test_the_rate_s_dft_and_the_spiking_magnitudes_run_to_the_same_bits(tmp_path, target,
                                                                       motifs) -> None:
    """The remaining motifs export writes; on a chip the magnitudes' matrices produce no
    axis (one neuron per bin) and amb's relay has one part, which the split and the integer
    rounding once refused."""
    frames = np.random.default_rng(2).standard_normal((4, 32))
    program = compile_graph(Graph.from_yaml(RANGE_MAGNITUDE), target,
                            calibration_inputs={"x": frames}, motifs=motifs, accuracy="off")
    _same_run(program, {"x": frames[1]}, tmp_path)


@pytest.mark.parametrize("kind", ["os, k: 6", "ca"])
def test_a_repeated_rd_chain_and_2d_cfar_round_trip_compact(tmp_path, kind) -> None:
    """Over max_weights the repeated DFTs are one shared Linear each, the CFAR's stencil an
    empty Linear with its kernel in metadata: still the same bits."""
    chain = Graph.from_yaml(RD_CFAR.replace("CFAR_KIND", kind))
    rng = np.random.default_rng(1)
    x = rng.standard_normal((2, 8, 16)) + 1j * rng.standard_normal((2, 8, 16))
    program = compile_graph(chain, "loihi2", calibration_inputs={"adc": x})
    graph, report = _same_run(program, {"adc": x[0]}, tmp_path, max_weights=4096)
    compact = [k for k in graph.nodes if k.endswith(".compact")]
    assert compact and all(graph.nodes[k].weight.size <= 4096 for k in compact)
    assert any(e.aspect == "weights" and "shared" in e.detail for e in report.outside)


def test_the_classifier_round_trips(tmp_path) -> None:
    from test_classifier_compile import TINY, _chain

    from compiler.classifier import save_weights

    rng = np.random.default_rng(3)
    w = {k: np.round(rng.normal(0, 0.7, s) * 8) / 8
         for k, s in TINY.weight_shapes("c", (8, 6)).items()}
    save_weights(tmp_path / "w.npz", w)
    op = TINY.model_copy(update={"weights": str(tmp_path / "w.npz")})
    g = _chain(op, {"object": 3, "frame": 5, "doppler": 6, "range": 8})
    program = compile_graph(g, target=None)
    _same_run(program, {"roi": rng.normal(1.0, 1.5, (3, 5, 6, 8))}, tmp_path)


def test_a_network_round_trips_through_an_artifact(tmp_path) -> None:
    net = _zoo()
    graph, report = export_network(net, dt_s=1e-5)
    write_nir(graph, report, tmp_path / "zoo.nir")
    (back,) = import_nir(tmp_path / "zoo.nir")
    loaded = load(save(back, tmp_path / "art"))
    x = {"x": np.random.default_rng(5).uniform(0, 1, size=(2, 3))}
    want, got = simulate(net, x, record_spikes=True), simulate(loaded, x, record_spikes=True)
    for pid, raster in want.spikes.items():
        np.testing.assert_array_equal(got.spikes[pid], raster, err_msg=pid)


def test_a_graph_from_another_tool_runs_to_the_nir_interpreters_spikes() -> None:
    """The zoo's NIR graph without radarsnn metadata: the subset importer's network fires as
    the NIR interpreter of test_nir_export does on the same input spikes."""
    graph, _ = export_network(_zoo())
    bare = nir.NIRGraph(nodes={k: type(n).from_dict({**n.to_dict(), "metadata": {}})
                               for k, n in graph.nodes.items()},
                        edges=graph.edges, metadata={})
    net = import_generic(bare, dt_s=1.0, n_steps=24)
    x = np.random.default_rng(2).uniform(0, 1, size=net.population["x.in"].size)
    ours = simulate(net, {"x.in": x}, mode="step", record_spikes=True)
    want = run_nir(bare, _input_rasters(net, {"x.in": x}), 24, dt=1.0)
    for key in ("a.lif", "b.cuba", "c.ramp", "d.li", "e.if"):
        np.testing.assert_array_equal(ours.spikes[key][0].reshape(24, -1), want[key],
                                      err_msg=key)
        assert want[key].any(), key
    np.testing.assert_array_equal(ours.outputs["y.output"].ravel(), want["y.output"].sum(0))


def test_subset_and_metadata_errors_name_the_node(tmp_path) -> None:
    g = nir.NIRGraph.from_list(nir.Linear(weight=np.ones((2, 2))),
                               nir.LI(tau=np.ones(2), r=np.ones(2), v_leak=np.zeros(2)))
    with pytest.raises(IRError, match="NIR node 'li': a LI must feed exactly one IF/LIF"):
        import_nir(g, dt_s=0.5)
    with pytest.raises(IRError, match="no step duration"):
        import_nir(g)
    graph, _ = export_network(_zoo())
    graph.nodes["a.w.d0"].metadata.pop("radarsnn_array_delays")
    with pytest.raises(ArtifactError, match=r"NIR node 'a.w.d0': the 'delays' array"):
        import_nir(graph)
    graph, _ = export_network(_zoo())
    graph.nodes["b.w.d0"].weight[0, 0] += 0.5  # trained further elsewhere: entries are stale
    with pytest.raises(ArtifactError, match=r"NIR node 'b.w.d0' differs .* edited after"):
        import_nir(graph)
    graph, _ = export_network(_zoo())  # a forged entry of 10^12 neurons allocates nothing
    entry = json.loads(graph.nodes["a.lif"].metadata["radarsnn_entry"])
    entry["shape"] = [["rep", 10**6], ["o", 10**6]]
    graph.nodes["a.lif"].metadata["radarsnn_entry"] = json.dumps(entry)
    with pytest.raises(ArtifactError, match=r"'a.lif' has 6 neurons, its radarsnn entry 10+$"):
        import_nir(graph)
    from backends.nir.importer import import_classifier

    with pytest.raises(IRError, match="exported by radarsnn.*import-nir"):
        import_classifier(graph, tmp_path / "w.npz")
    graph.metadata["radarsnn_round_trip"] = "9"
    with pytest.raises(ArtifactError, match="version '9'"):
        import_nir(graph)
