"""The ``lower`` pass: every IR node becomes spiking motifs or a host segment."""

from __future__ import annotations

import logging
from dataclasses import dataclass

from pydantic import BaseModel

from compiler.lowering import LoweringContext, default_registry, lower_graph
from compiler.passes.base import CompileContext, Pass
from compiler.passes.static_split import host_nodes
from compiler.program import CompiledProgram

__all__ = ["Lower"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Lower(Pass):
    """Lower the graph with ``ctx.lowering`` (default: :func:`compiler.lowering.default_registry`).

    Reads ``program.records["calibrate"]`` (per-node calibration) when present
    and stores, under ``records["lower"]``, the motif chosen for every node.

    Attributes
    ----------
    motifs : tuple of (str, str)
        The user's motif choices, node id or op name → motif (compile option ``motifs``).
    settings : tuple of models
        The motifs' typed options (:func:`compiler.compile.motif_settings`;
        ``compile_graph`` sets them; a model not given takes its defaults).

    Examples
    --------
    >>> from ir import Graph
    >>> g = Graph.from_dict({"name": "x", "nodes": [
    ...     {"id": "a", "op": "input", "shape": {"range": 4}},
    ...     {"id": "m", "op": "magnitude", "input": "a", "kind": "l1"},
    ...     {"id": "o", "op": "output", "input": "m"}]})
    >>> p = Lower().apply(CompileContext(), CompiledProgram(graph=g))
    >>> [(s.kind, s.node) for s in p.segments], p.records["lower"]["motifs"]["m"]
    ([('host', 'm'), ('host', 'o')], 'host')
    """

    name = "lower"
    motifs: tuple[tuple[str, str], ...] = ()
    settings: tuple[BaseModel, ...] = ()

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        registry = ctx.lowering or default_registry()
        calibration = program.records.calibration or {}
        split = program.records.static_splits
        lctx = LoweringContext(graph=program.graph, registry=registry, motifs=dict(self.motifs),
                               settings={type(s): s for s in self.settings},
                               calibration=getattr(calibration, "nodes", calibration),
                               target=ctx.target, host_pinned=frozenset(host_nodes(split)),
                               moving=frozenset(n for r in split for n in r["moving"]),
                               memo=ctx.memo)
        program.segments = lower_graph(lctx)
        program.records.lowering = {
            "motifs": {n: lctx.motif_for(n) for n in program.graph.topological_order()},
        }
        for node, motif in program.records.motifs.items():
            log.debug("node %r -> motif %s", node, motif)
        log.info("%d spiking segment(s), %d host node(s)", len(program.networks),
                 len(program.host_nodes))
        return program
