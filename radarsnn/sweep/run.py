"""Run a sweep on Dask: cells as tasks, records appended as they arrive, resumable.

The task graph per run: the calibration frames (one task), one compile per
point, and per slice of frames one frame task and one reference task per chain
(made once, shared by every point's cell on that slice), then one evaluation
task per cell.  Cells already in ``OUT/results.jsonl`` are skipped; the others
are appended as they finish, so a killed run loses only the cells in flight.

``scheduler``: ``None`` starts a ``LocalCluster`` (``workers`` processes of one
thread), ``"sync"`` runs every task in this process in spec order (tests,
debugging), anything else is the address of a running Dask scheduler.
Results do not depend on the choice: every random draw is seeded from the
frame index or the cell id (see :mod:`radarsnn.sweep.frames`).

Examples
--------
>>> import tempfile
>>> res = run_sweep("examples/sweeps/small.yaml", tempfile.mkdtemp(), scheduler="sync",
...                 quiet=True, figures=False)
>>> res.n_run, res.n_skipped, res.rows[0]["complete"]
(4, 0, True)
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backends.atomic import check_output
from ir.errors import CompileError
from radarsnn.sweep.cells import Canonical, CellKey, cell_key
from radarsnn.sweep.executors import DaskExecutor, SyncExecutor
from radarsnn.sweep.frames import folder_files, load_frames
from radarsnn.sweep.metrics import NODE_OPS, MetricRegistry, default_metrics
from radarsnn.sweep.results import (
    RESULTS_FILE,
    append_record,
    read_records,
    summarize,
    write_summary,
)
from radarsnn.sweep.spec import SweepSpec, load_spec
from radarsnn.sweep.tasks import CellTask, compile_point, evaluate_cell, reference_values

__all__ = ["SweepResult", "run_sweep", "plan_cells"]


@dataclass(frozen=True)
class SweepResult:
    """What :func:`run_sweep` did: cells run / skipped / failed, the summary rows, files."""

    n_cells: int
    n_run: int
    n_skipped: int
    n_failed: int
    rows: list[dict[str, Any]]
    out_dir: Path
    seconds: float
    figures: list[Path]


def _resolve_metrics(spec: SweepSpec, graph: dict, registry: MetricRegistry) -> list[dict]:
    from ir import Graph

    g = Graph.from_dict(graph)
    types = g.infer_types()
    out = []
    for m in spec.metrics:
        registry[m.name]  # noqa: B018 - raises for an unknown metric, naming the known ones
        node = m.node
        if node is None:
            op = NODE_OPS.get(m.name)
            found = [n for n in g.topological_order() if op and g.op(n).op == op]
            if len(found) != 1:
                raise CompileError(f"metric {m.key!r}: chain {g.name!r} has {len(found)} "
                                   f"{op or 'suitable'} nodes {found}; set the metric's `node`")
            node = found[0]
        if node not in types:
            raise CompileError(f"metric {m.key!r}: node {node!r} is not in chain {g.name!r}")
        out.append({"name": m.name, "key": m.key, "node": node,
                    "axes": list(types[node].axes), "options": dict(m.options)})
    return out


def _input_node(spec: SweepSpec, graph: dict) -> str:
    from ir import Graph

    inputs = Graph.from_dict(graph).input_ids()
    if spec.input is not None:
        if spec.input not in inputs:
            raise CompileError(f"sweep {spec.name!r}: input {spec.input!r} is not an input node "
                               f"of chain {graph['name']!r} (inputs {inputs})")
        return spec.input
    if len(inputs) != 1:
        raise CompileError(f"sweep {spec.name!r}: chain {graph['name']!r} has inputs {inputs}; "
                           "set `input:` to the one the frames feed")
    return inputs[0]


def _source_identity(spec: SweepSpec) -> dict[str, Any]:
    ident = spec.frames.model_dump(exclude={"n_frames", "frames_per_cell"})
    if spec.frames.source == "folder":
        every = spec.frames.model_copy(update={"n_frames": None})  # n_frames adds slices only
        scored, cal = folder_files(every, spec.base_dir)
        ident["files"] = [(f.name, f.stat().st_size) for f in scored + cal]
    return ident


def plan_cells(spec: SweepSpec, registry: MetricRegistry | None = None) -> list[dict[str, Any]]:
    """Every point of ``spec`` with its chain, input, metrics, id and cell ids (slice order).

    The point id hashes the chain's content, the compile arguments, the engine, the
    frame source (less ``n_frames``/``frames_per_cell``) and the resolved metrics; a
    cell id hashes the point id and the slice.  Raises :class:`CompileError` for a
    metric or input that the chain cannot give.
    """
    from ir import Graph
    from ir.interpreter import check_input

    registry = registry or default_metrics()
    source = _source_identity(spec)
    chains = {name: spec.chain_dict(name) for name in dict.fromkeys(
        p.chain for p in spec.points())}
    first = load_frames(spec.frames, spec.base_dir, 0, 1, calibration=True).arrays[0]
    per_chain = {}
    for name, graph in chains.items():
        node = _input_node(spec, graph)
        check_input(node, Graph.from_dict(graph).infer_types()[node], first)
        per_chain[name] = (node, _resolve_metrics(spec, graph, registry))
    slices = spec.slices()
    # the chain, the source and the metrics serialised once, not once per point
    keys = {name: CellKey(graph) for name, graph in chains.items()}
    same = {name: Canonical.of(metrics) for name, (_, metrics) in per_chain.items()}
    source = Canonical.of(source)
    plan = []
    for p in spec.points():
        node, metrics = per_chain[p.chain]
        point = keys[p.chain].then(p.compile_args, p.mode, p.out_of_range, source,
                                   same[p.chain]).hex()
        plan.append({"point": point, "params": p.params, "chain": p.chain, "graph": chains[p.chain],
                     "compile_args": p.compile_args, "mode": p.mode,
                     "out_of_range": p.out_of_range, "input": node,
                     "metrics": metrics, "slices": slices,
                     "cells": [cell_key(point, s) for s in slices]})
    return plan


def _submit(ex, spec: SweepSpec, plan: list[dict], todo: set[str], registry) -> list:
    """Submit the tasks the missing cells need; return the cells' futures (slice-major)."""
    base, source = spec.base_dir, cell_key(_source_identity(spec))
    needed = [p for p in plan if todo & set(p["cells"])]
    cal = ex.submit(load_frames, spec.frames, base, 0, spec.frames.calibration_frames, True,
                    key=f"sweep-calibration-{source}")
    programs = {p["point"]: ex.submit(compile_point, p["graph"], p["compile_args"], p["input"],
                                      cal, key=f"sweep-compile-{p['point']}") for p in needed}
    futures = []
    keys = {p["chain"]: CellKey(p["graph"]) for p in needed}  # each chain hashed once
    for i, (a, b) in enumerate(spec.slices()):
        here = [p for p in needed if p["cells"][i] in todo]
        if not here:
            continue
        frames = ex.submit(load_frames, spec.frames, base, a, b, False,
                           key=f"sweep-frames-{cell_key(source, a, b)}")
        refs = {}
        for p in here:
            if p["chain"] not in refs:
                nodes = sorted({m["node"] for m in p["metrics"]})
                refs[p["chain"]] = ex.submit(
                    reference_values, p["graph"], p["input"], frames, nodes,
                    key=f"sweep-reference-{keys[p['chain']].then(nodes, source, a, b).hex()}")
            cell = p["cells"][i]
            task = CellTask(cell=cell, point=p["point"], params=p["params"], slice=(a, b),
                            input=p["input"], mode=p["mode"], metrics=p["metrics"],
                            seed=int(cell[:8], 16), out_of_range=p["out_of_range"])
            futures.append(ex.submit(evaluate_cell, task, programs[p["point"]], frames,
                                     refs[p["chain"]], registry, key=f"sweep-cell-{cell}"))
    return futures


def run_sweep(spec: SweepSpec | str | Path, out_dir: str | Path, *, scheduler: str | None = None,
              workers: int | None = None, processes: bool = True, quiet: bool = False,
              metrics: MetricRegistry | None = None, max_cells: int | None = None,
              figures: bool = True) -> SweepResult:
    """Run (or resume) a sweep; write ``results.jsonl``, ``summary.json/.csv`` and figures.

    Parameters
    ----------
    spec : SweepSpec or path
        The sweep (a path is read with :func:`~radarsnn.sweep.spec.load_spec`).
    out_dir : str or Path
        Output folder (created); its ``results.jsonl`` is read first and skipped cells
        are not recomputed.
    scheduler : str, optional
        ``None`` (a new LocalCluster), ``"sync"`` (in this process), or a scheduler address.
    workers : int, optional
        LocalCluster worker processes (default 2), one thread each.
    processes : bool
        LocalCluster workers as processes (False: threads of this process).
    quiet : bool
        No progress bar.
    metrics : MetricRegistry, optional
        Metric implementations (default :func:`~radarsnn.sweep.metrics.default_metrics`).
    max_cells : int, optional
        Stop after this many new cells (the rest stays for the next run).
    figures : bool
        Draw the spec's ``figures`` into ``OUT/figures``.

    Returns
    -------
    SweepResult

    Raises
    ------
    CompileError
        An invalid spec, metric or input node.
    RadarConfigError
        A frame source that cannot give frames.
    ArtifactError
        ``out_dir`` exists and is not a folder (or is no valid path).
    """
    from tqdm import tqdm

    start = time.perf_counter()
    if max_cells is not None and (isinstance(max_cells, bool) or not isinstance(max_cells, int)
                                  or max_cells < 0):
        raise CompileError(f"max_cells={max_cells!r}: give a whole number of cells >= 0 "
                           "(0: plan only)")
    spec = spec if isinstance(spec, SweepSpec) else load_spec(spec)
    registry = metrics or default_metrics()
    out = check_output(out_dir, folder=True)  # not a file, a device, a NUL byte
    out.mkdir(parents=True, exist_ok=True)
    results = out / RESULTS_FILE
    plan = plan_cells(spec, registry)
    cells = [c for p in plan for c in p["cells"]]
    done = {r["cell"] for r in read_records(results)}
    todo = set(cells) - done
    n_run = 0
    if todo and max_cells != 0:
        ex = SyncExecutor() if scheduler == "sync" else DaskExecutor(scheduler, workers, processes)
        # disable=None: no bar when stderr is not a terminal (a log file, a CI job)
        bar = tqdm(total=len(todo), desc=spec.name, unit="cell", disable=True if quiet else None,
                   file=sys.stderr)
        try:
            futures = _submit(ex, spec, plan, todo, registry)
            for fut in ex.as_completed(futures):
                append_record(results, fut.result())
                n_run += 1
                bar.update(1)
                if max_cells is not None and n_run >= max_cells:
                    break
        finally:
            bar.close()
            ex.close()
    records = read_records(results)
    rows = summarize(records, [{"point": p["point"], "params": p["params"], "cells": p["cells"],
                                "metrics": [(m["key"], m["name"]) for m in p["metrics"]]}
                               for p in plan], registry)
    write_summary(rows, out)
    drawn: list[Path] = []
    if figures and spec.figures:
        from radarsnn.sweep.figures import draw_figures

        drawn = draw_figures(spec.figures, rows, out / "figures",
                             {m.key: m.name for m in spec.metrics})
    mine = set(cells)
    failed = sum(1 for r in records if r["cell"] in mine and r.get("error"))
    return SweepResult(n_cells=len(cells), n_run=n_run, n_skipped=len(mine & done),
                       n_failed=failed, rows=rows, out_dir=out,
                       seconds=time.perf_counter() - start, figures=drawn)
