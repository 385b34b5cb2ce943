"""The ``verify`` pass: the graph must verify before anything else runs."""

from __future__ import annotations

from dataclasses import dataclass

from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram

__all__ = ["Verify"]


@dataclass(frozen=True)
class Verify(Pass):
    """Run :meth:`ir.Graph.verify` (raises :class:`ir.errors.IRError` naming the node).

    Examples
    --------
    >>> from ir import Graph
    >>> g = Graph.from_dict({"name": "x", "nodes": [
    ...     {"id": "a", "op": "input", "shape": {"range": 4}},
    ...     {"id": "o", "op": "output", "input": "a"}]})
    >>> Verify().apply(CompileContext(), CompiledProgram(graph=g)).graph is g
    True
    """

    name = "verify"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        program.graph.verify()
        return program
