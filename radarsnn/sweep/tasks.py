"""The pure functions a sweep's workers run: compile a point, evaluate a cell.

Every function here is deterministic in its arguments (no global state, no
clock in the results) so a cell's record is the same on any worker, in any
order.  The runner (:mod:`radarsnn.sweep.run`) wires them into a task graph:
frames and the reference are made once per slice and shared by the cells that
read them.

Examples
--------
>>> from ir import Graph
>>> from radarsnn.sweep.frames import FrameBatch
>>> g = {"name": "x", "nodes": [{"id": "a", "op": "input", "shape": {"range": 3}},
...      {"id": "m", "op": "magnitude", "input": "a", "kind": "square"},
...      {"id": "o", "op": "output", "input": "m"}]}
>>> fr = FrameBatch((0,), [np.array([1.0, -2.0, 3.0])], [()])
>>> reference_values(g, "a", fr, ["m"])[0]["m"].tolist()
[1.0, 4.0, 9.0]
>>> program = compile_point(g, {"target": None, "options": {}}, "a", fr)
>>> cell = CellTask(cell="c0", point="p0", params={}, slice=(0, 1), input="a",
...                 mode="auto", metrics=[], seed=1)
>>> rec = evaluate_cell(cell, program, fr, reference_values(g, "a", fr, []), None)
>>> rec["cost"]["frames"], rec["error"]
(1, None)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ir.errors import RadarSNNError, SimulationError
from radarsnn.sweep.cost import run_cost, static_cost
from radarsnn.sweep.frames import FrameBatch

__all__ = ["CellTask", "CompileFailure", "reference_values", "compile_point", "evaluate_cell"]


@dataclass(frozen=True)
class CompileFailure:
    """A point whose chain did not compile: the error, as its cells will record it."""

    error: str


@dataclass(frozen=True)
class CellTask:
    """What a worker needs to evaluate one cell besides the program, frames and reference.

    ``metrics`` are resolved metric specs: dicts with ``name``, ``key`` (summary
    column), ``node``, ``axes`` and ``options``; ``out_of_range`` is the simulator's
    policy for inputs outside an encoder's range (``clip``: what a chip's code does,
    counted in the cost as ``clipped``).
    """

    cell: str
    point: str
    params: dict[str, Any]
    slice: tuple[int, int]
    input: str
    mode: str
    metrics: list[dict[str, Any]] = field(default_factory=list)
    seed: int = 0
    out_of_range: str = "clip"


def reference_values(graph: dict, input_node: str, frames: FrameBatch,
                     nodes: list[str]) -> list[dict[str, np.ndarray]]:
    """Per frame, the golden values (``ir.evaluate`` of the chain) of ``nodes``."""
    from ir import Graph, evaluate

    g = Graph.from_dict(graph)
    keep = set(nodes)
    return [{k: v for k, v in evaluate(g, {input_node: x}).items() if k in keep}
            for x in frames.arrays]


def compile_point(graph: dict, compile_args: dict[str, Any], input_node: str,
                  calibration: FrameBatch):
    """Compile the chain with one point's arguments, calibrated on ``calibration``.

    Returns
    -------
    CompiledProgram or CompileFailure
        A failure (any :class:`~ir.errors.RadarSNNError`, e.g. a ``BudgetError`` of a
        target) is returned, not raised, so that the sweep records it per cell.
    """
    from compiler.compile import compile_graph
    from ir import Graph
    from ir.interpreter import check_input

    args = dict(compile_args)
    target = args.pop("target", None)
    try:
        g = Graph.from_dict(graph)
        t = g.infer_types()[input_node]
        cal = np.stack([check_input(input_node, t, a) for a in calibration.arrays])
        return compile_graph(g, target, calibration_inputs={input_node: cal}, **args)
    except RadarSNNError as err:
        return CompileFailure(f"{type(err).__name__}: {err}")


def _frame_metrics(cell: CellTask, values, reference, frames: FrameBatch, i: int,
                   registry) -> dict[str, dict[str, float]]:
    from radarsnn.sweep.metrics import FrameData

    out = {}
    for m in cell.metrics:
        node = m["node"]
        if node not in values:
            raise SimulationError(f"metric {m['key']!r}: node {node!r} has no value in the "
                                  "compiled program (fused away?); name another node")
        data = FrameData(values=values, reference=reference, node=node, axes=tuple(m["axes"]),
                         truth=tuple(frames.truth[i]),
                         label=None if frames.labels is None else frames.labels[i],
                         options=m["options"], seed=cell.seed)
        out[m["key"]] = registry[m["name"]].update(data)
    return out


def _add(total: dict, part: dict) -> None:
    for k, v in part.items():
        total[k] = total.get(k, 0) + v


def evaluate_cell(cell: CellTask, program, frames: FrameBatch,
                  reference: list[dict[str, np.ndarray]], registry) -> dict[str, Any]:
    """Run ``program`` on each frame of the slice; sum metric statistics and run costs.

    Returns
    -------
    dict
        The cell's record: ``cell``, ``point``, ``params``, ``slice``, ``metrics``
        (per metric key, its additive sums), ``cost`` (static cost and run sums),
        ``error`` (None, or the compile/simulation error), ``seconds`` and
        ``cpu_seconds`` (wall and process CPU time: the only fields that vary by run).
    """
    from backends.reference.program import program_plans, run_program

    start, cpu = time.perf_counter(), time.process_time()
    record: dict[str, Any] = {"cell": cell.cell, "point": cell.point, "params": cell.params,
                              "slice": list(cell.slice), "metrics": {}, "cost": {},
                              "error": None}
    if isinstance(program, CompileFailure):
        record["error"] = program.error
    else:
        try:
            plans = program_plans(program)
            sums: dict[str, dict] = {m["key"]: {} for m in cell.metrics}
            runs: dict[str, int] = {}
            for i, x in enumerate(frames.arrays):
                result = run_program(program, {cell.input: x}, mode=cell.mode, plans=plans,
                                     out_of_range=cell.out_of_range)
                for key, part in _frame_metrics(cell, result.values, reference[i], frames, i,
                                                registry).items():
                    _add(sums[key], part)
                _add(runs, run_cost(result))
            record["metrics"] = sums
            record["cost"] = {**static_cost(program), **runs}
        except RadarSNNError as err:
            record["error"] = f"{type(err).__name__}: {err}"
    record["seconds"] = round(time.perf_counter() - start, 3)
    record["cpu_seconds"] = round(time.process_time() - cpu, 3)
    return record
