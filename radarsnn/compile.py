"""``radarsnn.compile_graph``: the compiler with the reference simulator measuring what it keeps.

:func:`compiler.compile.compile_graph` is the pass pipeline; given a simulator it
measures the per-stage accuracy contract on held-back frames and chooses the motifs
(:mod:`compiler.accuracy`). This is that call with the reference simulator, which is
what a user wants by default: a chain that loses what the conventional chain detects
is refused (:class:`~ir.errors.AccuracyError`, naming the stage) unless
``accuracy="warn"``.
"""

from __future__ import annotations

from typing import Any

from backends.reference import ReferenceSimulator
from compiler.compile import TargetSpec
from compiler.compile import compile_graph as _compile_graph
from compiler.program import CompiledProgram

__all__ = ["compile_graph"]


def compile_graph(graph: Any, target: TargetSpec = "loihi2", *, simulator: Any = None,
                  accuracy: str = "error", **kwargs: Any) -> CompiledProgram:
    """:func:`compiler.compile.compile_graph` measured by ``simulator`` (default: the reference).

    Parameters
    ----------
    graph, target
        As :func:`compiler.compile.compile_graph`.
    simulator : Simulator, optional
        Default :class:`backends.reference.ReferenceSimulator`.
    accuracy : {"error", "warn", "off"}
        What to do when no configuration keeps the contract.
    **kwargs
        Every other argument of :func:`compiler.compile.compile_graph`.

    Returns
    -------
    CompiledProgram
        ``program.records.accuracy`` holds the contract measured;
        ``program.records.extra["motif_selection"]`` the configurations tried.
    """
    return _compile_graph(graph, target, simulator=simulator or ReferenceSimulator(),
                          accuracy=accuracy, **kwargs)
