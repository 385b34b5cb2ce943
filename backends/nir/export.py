r"""Export spiking networks and compiled programs to NIR graphs (PyPI ``nir`` 1.0).

Every population becomes NIR nodes of flat shape ``(size,)`` (row-major over its
axes, listed in metadata ``radarsnn_shape``), named after its id with ``/``
replaced by ``.`` (``f/out`` → ``f.out``; ids are ``<IR node>/<name>``, so
every name traces to its IR node, also stored as ``radarsnn_node``):

* a source population (encoder) → ``Input``; the value → spike code runs
  outside the graph (``outside`` entry; code in ``radarsnn_encoder``);
* a neuron population → ``IF``/``LIF``/``CubaLIF`` (+ ``I``/``LI`` current
  stage), see :mod:`backends.nir.neurons`;
* a projection → one ``Linear`` per delay class ``d`` (``<proj>.d<d>``) with
  the block-diagonal weights of every repetition (stencils expanded), preceded
  by a ``Delay`` of ``d·dt`` when ``d > 0`` (``<proj>.delay<d>``); an ``Affine``
  when it carries the target's constant bias; over ``max_weights`` dense
  entries, one compact ``<proj>.compact`` node (:mod:`backends.nir.entries`);
* a decoder → an ``Output`` ``<port>.output`` fed by the population's spikes; the
  readout runs outside (``radarsnn_decoder``).

Every population and projection node also carries its artifact entry
(:mod:`backends.nir.entries`), so :func:`backends.nir.import_nir` rebuilds the
network exactly.

NIR sums the inputs of a node with several incoming edges, as our currents add.
Synapses come from the Brian2 expanders (a table keyed by projection type); how a
kind is lowered is read from the exporter's own type-keyed table ``_LOWERING``,
never from a test of the projection's kind.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import NeuronParams
>>> from compiler.snn.examples import tiny_network
>>> net = tiny_network(params=NeuronParams(v_th=2.0, reset="value"),
...                    delays=np.array([[0], [2]]), scoped=True)
>>> graph, report = export_network(net)
>>> sorted(graph.nodes)
['x.in', 'y.out', 'y.output', 'y.w.d0', 'y.w.d2', 'y.w.delay2']
>>> sorted(graph.edges)[:2]
[('x.in', 'y.w.d0'), ('x.in', 'y.w.delay2')]
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterable
from pathlib import Path

import nir
import numpy as np

from backends.atomic import check_output, write_atomic_files
from backends.brian2.synapses import dense_weights, expand_projection
from backends.nir.entries import (
    ROUND_TRIP_VERSION,
    compact_node,
    network_entry,
    population_meta,
    projection_meta,
)
from backends.nir.neurons import bias_of, neuron_nodes, origin_node, scaled_bias
from backends.nir.report import ExportReport
from compiler.program import CompiledProgram
from compiler.snn.network import SpikingNetwork
from compiler.snn.projections import MatrixProjection, StencilProjection
from compiler.snn.resonator import ResonatorParams
from ir.errors import ArtifactError

__all__ = ["export_network", "export_program", "write_nir", "nir_name", "MAX_WEIGHTS",
           "CONVENTION"]

#: Largest dense ``Linear`` (entries) written before refusing (128 MiB of float64).
MAX_WEIGHTS = 1 << 24

#: The discretisation every exported graph assumes (graph metadata ``radarsnn_convention``).
CONVENTION = ("forward Euler with step radarsnn_dt_s; per step: current stage, then voltage "
              "stage, both reading this step's input; Delay in multiples of dt; spike when "
              "v > v_threshold, then v = v_reset (compiler.snn.neurons)")


#: How each projection type becomes dense ``Linear`` nodes, by type (the exporter's own table):
#: ``(projection, source) -> (wording, exact)``; a matrix is exact when applied once.
_LOWERING = {
    MatrixProjection: lambda p, src: ("shared matrix instantiated as", src.size == p.n_in),
    StencilProjection: lambda p, src: ("stencil expanded to", False),
}


def nir_name(item_id: str, prefix: str = "") -> str:
    """The NIR node name of a population/projection/port id (``/`` → ``.``).

    Examples
    --------
    >>> nir_name("rd/out", prefix="n1.")
    'n1.rd.out'
    """
    return prefix + item_id.replace("/", ".")


def _meta(**items: object) -> dict[str, str]:
    return {f"radarsnn_{k}": v if isinstance(v, str) else json.dumps(v) for k, v in
            items.items()}


def _put(nodes: dict, name: str, node: nir.NIRNode, item: str) -> None:
    if name in nodes:
        raise ArtifactError(f"{item!r}: its NIR node name {name!r} is already taken by another "
                            "population, projection or port ('/' becomes '.'); rename one",
                            node=item)
    nodes[name] = node


def _add_network(net: SpikingNetwork, k: int, nodes: dict, edges: list, report: ExportReport,
                 dt_s: float, prefix: str, max_weights: int) -> bool:
    """Add ``net`` (network number ``k``) to ``nodes``/``edges``; True if a node is compact."""
    net.validate()
    pops = net.population
    for pop in net.populations:
        if isinstance(pop.params, ResonatorParams):
            node = origin_node(pop.id, pop.origin)
            raise ArtifactError(f"node {node!r} (population {pop.id!r}, motif 'resonator'): NIR "
                                "has no resonate-and-fire neuron, so it cannot be exported; "
                                f"compile it with another DFT motif (--motif {node}=time, or "
                                f"motifs={{{node!r}: 'time'}} in Python) and export that",
                                node=node)
    encoders = {e.population: e for e in net.encoders}
    entry, exit_ = {}, {}
    affine_bias = {}  # target pop -> the projection that carries its constant bias
    for proj in net.projections:
        tgt = pops[proj.target].params
        b = bias_of(pops[proj.target])
        dense = pops[proj.source].size * pops[proj.target].size <= max_weights  # not compact
        if (b and dense and tgt.dv == 0 and tgt.du == 1.0 and proj.target not in affine_bias):
            affine_bias[proj.target] = proj.id
    for index, pop in enumerate(net.populations):
        name = nir_name(pop.id, prefix)
        if pop.source:
            enc = encoders[pop.id]
            meta = _meta(population=pop.id, node=enc.node or origin_node(pop.id, pop.origin),
                         shape=pop.shape, encoder=enc.model_dump(mode="json"))
            _put(nodes, name, nir.Input(input_type={"input": np.array([pop.size])},
                                        metadata={**meta, **population_meta(pop, index, k)}),
                 pop.id)
            report.add(pop.id, "encoder", "outside",
                       f"{enc.code.type} code of port {enc.port!r} (split {enc.split}) turns "
                       f"values into spikes before the graph; Input {name} carries the spikes")
            entry[pop.id] = exit_[pop.id] = name
        else:
            new, entry[pop.id], exit_[pop.id] = neuron_nodes(
                pop, name, dt_s, report, bias_elsewhere=pop.id in affine_bias)
            new[name].metadata["radarsnn_shape"] = json.dumps(pop.shape)
            new[name].metadata.update(population_meta(pop, index, k))
            edges += list(zip(list(new)[:-1], list(new)[1:], strict=True))
            for key, node in new.items():
                _put(nodes, key, node, pop.id)
        report.nodes[name] = pop.id
    compact = False
    for index, proj in enumerate(net.projections):
        src, tgt = pops[proj.source], pops[proj.target]
        if src.size * tgt.size > max_weights:
            compact = True
            node, how = compact_node(proj, src, tgt, max_weights)
            name = nir_name(f"{proj.id}.compact", prefix)
            node.metadata = {**_meta(projection=proj.id, node=origin_node(proj.id, proj.origin)),
                             **projection_meta(proj, index, k, node.weight)}
            _put(nodes, name, node, proj.id)
            edges += [(exit_[proj.source], name), (name, entry[proj.target])]
            report.nodes[name] = proj.id
            report.add(proj.id, "weights", "outside", how)
            continue
        syn = expand_projection(proj, src, tgt)
        delays = [int(d) for d in np.unique(syn.delay)] or [0]
        for d in delays:
            w = dense_weights(syn, src.size, tgt.size, delay=d)
            lin = nir_name(f"{proj.id}.d{d}", prefix)
            meta = _meta(projection=proj.id, node=origin_node(proj.id, proj.origin), delay_steps=d)
            if d == delays[0]:
                meta.update(projection_meta(proj, index, k, w))
            if affine_bias.get(proj.target) == proj.id and d == delays[0]:
                bias = scaled_bias(tgt)
                _put(nodes, lin, nir.Affine(weight=w, bias=bias, metadata=meta), proj.id)
            else:
                _put(nodes, lin, nir.Linear(weight=w, metadata=meta), proj.id)
            head = exit_[proj.source]
            if d:
                delay = nir_name(f"{proj.id}.delay{d}", prefix)
                _put(nodes, delay, nir.Delay(delay=np.full(src.size, d * dt_s)), proj.id)
                edges.append((head, delay))
                head = delay
            edges += [(head, lin), (lin, entry[proj.target])]
            report.nodes[lin] = proj.id
        how, exact = _LOWERING[type(proj)](proj, src)
        kind = "exact" if exact else "lowered"
        report.add(proj.id, "weights", kind,
                   f"{how} a dense {tgt.size} x {src.size} Linear per delay class "
                   f"({len(syn)} synapses)")
        if delays != [0]:
            report.add(proj.id, "delays", "lowered",
                       f"per-synapse delays {delays} as one Delay + Linear per delay class")
    for dec in net.decoders:
        name = nir_name(f"{dec.port}.output", prefix)
        pop = pops[dec.population]
        _put(nodes, name, nir.Output(output_type={"output": np.array([pop.size])},
                                     metadata=_meta(port=dec.port, node=dec.node or dec.port,
                                                    decoder=dec.model_dump(mode="json"))),
             dec.port)
        edges.append((exit_[dec.population], name))
        report.add(dec.port, "decoder", "outside",
                   f"{dec.kind} readout of {dec.population} (combine {dec.combine}) runs after "
                   f"the graph on the spikes of Output {name}")
        report.nodes[name] = dec.port
    return compact


def export_network(
    network: SpikingNetwork, *, dt_s: float = 1.0, max_weights: int = MAX_WEIGHTS
) -> tuple[nir.NIRGraph, ExportReport]:
    """Export one spiking network to a NIR graph.

    Parameters
    ----------
    network : SpikingNetwork
        The network (validated here).
    dt_s : float
        Duration of one step, the ``dt`` of the NIR time constants and delays.
    max_weights : int
        A projection whose dense ``Linear`` would exceed this many entries is written
        compact (:func:`backends.nir.entries.compact_node`; the graph then needs
        ``type_check=False`` in ``nir.read``).

    Returns
    -------
    graph : nir.NIRGraph
    report : ExportReport
        What is exact, lowered, or outside NIR.

    Raises
    ------
    NetworkError
        If the network does not validate.
    ArtifactError
        For a projection array over the 2^24 entries a NIR file may hold per dataset.
    """
    return _export([network], [], dt_s, max_weights, name=network.name)


def export_program(
    program: CompiledProgram, *, stages: Iterable[str] | None = None,
    dt_s: float | None = None, max_weights: int = MAX_WEIGHTS
) -> tuple[nir.NIRGraph, ExportReport]:
    """Export a compiled program's spiking networks (or the chosen stages) to one NIR graph.

    Parameters
    ----------
    program : CompiledProgram
        The compiled chain.
    stages : iterable of str, optional
        IR node ids; only networks with a population of one of these nodes are exported.
    dt_s : float, optional
        Duration of one step; default the target profile's ``time_step_s`` (1 s for a
        program compiled without a target or a profile without one).
    max_weights : int
        As for :func:`export_network`.

    Returns
    -------
    graph, report
        With several networks, names are prefixed ``n<k>.``; host segments are
        ``outside`` entries.

    Raises
    ------
    ArtifactError
        If no spiking network matches, or a projection array is over 2^24 entries.
    """
    wanted = None if stages is None else set(stages)
    nets, host = [], []
    for seg in program.segments:
        if seg.kind == "host":
            host.append(seg.node)
        elif wanted is None or any(origin_node(p.id, p.origin) in wanted
                                   for p in seg.network.populations):
            nets.append(seg.network)
    if not nets:
        raise ArtifactError(f"program {program.graph.name!r}: no spiking network to export "
                            f"(stages {sorted(wanted) if wanted else 'all'}); choose IR nodes "
                            "that were lowered to spikes")
    if dt_s is None:
        dt_s = float(program.target.time_step_s or 1.0) if program.target is not None else 1.0
    return _export(nets, host, dt_s, max_weights, name=program.graph.name)


def _export(nets: list[SpikingNetwork], host: list[str], dt_s: float, max_weights: int,
            name: str) -> tuple[nir.NIRGraph, ExportReport]:
    """The NIR graph and report of ``nets`` (``n<k>.``-prefixed when several)."""
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise ArtifactError(f"NIR export of {name!r}: dt_s must be a positive number of "
                            f"seconds, got {dt_s}")
    nodes: dict[str, nir.NIRNode] = {}
    edges: list[tuple[str, str]] = []
    report = ExportReport()
    compact = False
    for k, net in enumerate(nets):
        compact |= _add_network(net, k, nodes, edges, report, dt_s,
                                f"n{k}." if len(nets) > 1 else "", max_weights)
    for node in host:
        report.add(node, "host segment", "outside",
                   "evaluated on the host, outside the spiking networks")
    meta = _meta(dt_s=dt_s, convention=CONVENTION, name=name,
                 networks=[n.name for n in nets], n_steps=[n.n_steps for n in nets],
                 artifacts=[network_entry(n) for n in nets], round_trip=ROUND_TRIP_VERSION,
                 max_weights=max_weights)
    return nir.NIRGraph(nodes=nodes, edges=edges, metadata=meta, type_check=not compact), report


def write_nir(graph: nir.NIRGraph, report: ExportReport, path: str | Path) -> ExportReport:
    """Write ``graph`` to ``path`` (``nir.write``) and the report next to it as JSON, atomically.

    The report goes to ``<path without suffix>.report.json``; its ``path`` is set.  Both
    files are written whole into hidden temporaries first and renamed into place only
    then (:func:`backends.atomic.write_atomic_files`): a full disk or a killed process
    leaves the previous pair (or nothing), never a truncated ``.nir``.

    Raises
    ------
    ArtifactError
        ``path`` (or its report's path) is no place for a file (a device such as
        ``/dev/null``, a folder, a NUL byte), or a file cannot be written (naming
        it; nothing is changed).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> g = nir.NIRGraph.from_list(nir.Linear(weight=np.ones((1, 2))))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     r = write_nir(g, ExportReport(), pathlib.Path(d) / "net.nir")
    ...     sorted(p.name for p in pathlib.Path(d).iterdir())
    ['net.nir', 'net.report.json']
    """
    path = check_output(path)
    report_path = check_output(path.with_suffix(".report.json"))
    buffer = io.BytesIO()
    nir.write(buffer, graph)  # in memory: h5py never writes to a disk that may be full
    report.path = str(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic_files({path: buffer.getvalue(), report_path: report.to_bytes()},
                           durable=True)
    except OSError as exc:
        raise ArtifactError(f"cannot write the NIR export to {path}: "
                            f"{exc.strerror or exc} (nothing was written; free some space or "
                            "give another path)") from exc
    return report
