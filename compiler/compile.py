"""``compile_graph``: a radar chain in, a :class:`~compiler.program.CompiledProgram` out.

The pipeline is a list of passes (see :mod:`compiler.passes`) run in order on
an explicit :class:`~compiler.passes.CompileContext`:

``verify`` → ``lower`` (each node into its chosen motif or a host segment).

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 4}},
...     {"id": "o", "op": "output", "input": "a"}]})
>>> program = compile_graph(g)
>>> [s.kind for s in program.segments]
['host']
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from compiler.lowering import LoweringRegistry, default_registry
from compiler.passes import CompileContext, Pass, Verify, run_pipeline
from compiler.passes.base import Progress
from compiler.passes.lower import Lower
from compiler.program import CompiledProgram
from ir import Graph

__all__ = ["compile_graph", "default_pipeline"]


def default_pipeline(options: Mapping[str, Any]) -> list[Pass]:
    """The passes ``compile_graph`` runs, in order, for the given options."""
    return [Verify(), Lower()]


def compile_graph(graph: Graph | str | Path, target: Any = None, *,
                  motifs: Mapping[str, str] | None = None, calibration: str = "static",
                  calibration_inputs: Mapping[str, np.ndarray] | None = None,
                  time_steps: int | None = None, weight_bits: int | None = None,
                  registry: LoweringRegistry | None = None,
                  progress: Progress | None = None) -> CompiledProgram:
    """Compile a radar chain into spiking and host segments.

    Parameters
    ----------
    graph : Graph or path
        The chain (a path is read with :meth:`ir.Graph.from_yaml`).
    target : object, optional
        The hardware profile (None: unbounded).
    motifs : mapping, optional
        Motif per node id or op name (e.g. ``{"dft": "time", "mag": "host"}``).
    calibration : {"static", "per-input"}
        The calibration policy.
    calibration_inputs : mapping, optional
        Sample arrays by input node id for calibration.
    time_steps : int, optional
        Override of the per-motif time window.
    weight_bits : int, optional
        Quantize weights to this many bits (None: exact floats).
    registry : LoweringRegistry, optional
        Lowering rules (default :func:`compiler.lowering.default_registry`).
    progress : callable, optional
        ``progress(pass_name, message)`` on long work.

    Returns
    -------
    CompiledProgram
    """
    if isinstance(graph, (str, Path)):
        graph = Graph.from_yaml(Path(graph))
    options = {"motifs": dict(motifs or {}), "calibration": calibration,
               "time_steps": time_steps, "weight_bits": weight_bits}
    ctx = CompileContext(target=target, options=options,
                         calibration_inputs=dict(calibration_inputs or {}),
                         lowering=registry or default_registry())
    if progress is not None:
        ctx.progress = progress
    program = CompiledProgram(graph=graph, options=options, target=target)
    return run_pipeline(default_pipeline(options), ctx, program)
