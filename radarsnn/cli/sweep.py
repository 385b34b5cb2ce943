"""The ``radarsnn sweep`` sub-command: run (or resume) a sweep file.

``radarsnn sweep SPEC.yaml [--scheduler ADDR] [--workers N] [--out DIR] [--quiet] [--json]``
— :func:`add_parsers` registers it on ``radarsnn``'s sub-parsers; :func:`run_command`
does the work and prints a table of the summary (or, with ``--json``, one JSON
object: the counts, the output files and the summary rows).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from radarsnn.sweep.run import SweepResult, run_sweep

__all__ = ["add_parsers", "add_parser", "run_command", "format_rows"]


def format_rows(result: SweepResult) -> str:
    """A plain-text table of the summary: params, then each metric's figures, then cost.

    Examples
    --------
    >>> from pathlib import Path
    >>> rows = [{"point": "p", "params": {"time_steps": 8}, "complete": True, "error": None,
    ...          "metrics": {"cfar": {"sensitivity": 0.5}}, "cost": {"neurons": 4}}]
    >>> r = SweepResult(1, 1, 0, 0, rows, Path("."), 0.0, [])
    >>> print(format_rows(r))
    time_steps  cfar.sensitivity  neurons
    8           0.5               4
    """
    table = []
    for row in result.rows:
        cells = {k: str(v) for k, v in row["params"].items()}
        for key, figures in row["metrics"].items():
            cells |= {f"{key}.{k}": f"{v:.5g}" if isinstance(v, float) else str(v)
                      for k, v in figures.items()}
        cells |= {k: str(row["cost"][k]) for k in ("neurons", "synapses", "cores", "steps")
                  if k in row["cost"]}
        if row["error"]:
            cells["error"] = row["error"].splitlines()[0][:60]
        elif not row["complete"]:
            cells["error"] = "incomplete"
        table.append(cells)
    # Not tabulate: its "plain" format is these four lines of width arithmetic, and the sweep
    # extra (dask, tqdm) would carry one more dependency for it; the cells are formatted above.
    columns = list(dict.fromkeys(k for r in table for k in r))
    widths = {c: max(len(c), *(len(r.get(c, "")) for r in table)) for c in columns}
    lines = ["  ".join(c.ljust(widths[c]) for c in columns).rstrip()]
    lines += ["  ".join(r.get(c, "").ljust(widths[c]) for c in columns).rstrip() for r in table]
    return "\n".join(lines)


def run_command(args: argparse.Namespace) -> int:
    """Run the sweep the parsed ``args`` describe; print the summary; return 0."""
    spec = Path(args.spec)
    out = Path(args.out) if args.out else Path("sweeps") / spec.stem
    result = run_sweep(spec, out, scheduler=args.scheduler, workers=args.workers,
                       quiet=args.quiet or args.json, max_cells=args.max_cells)
    if args.json:
        print(json.dumps({"cells": result.n_cells, "run": result.n_run,
                          "skipped": result.n_skipped, "failed": result.n_failed,
                          "seconds": round(result.seconds, 3), "out": str(result.out_dir),
                          "figures": [str(p) for p in result.figures], "rows": result.rows},
                         sort_keys=True))
        return 0
    print(format_rows(result))
    print(f"\n{result.n_run} cells run, {result.n_skipped} skipped, {result.n_failed} failed "
          f"of {result.n_cells} in {result.seconds:.1f} s; results in {result.out_dir}")
    return 0


def add_parsers(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``sweep`` sub-command to ``subparsers`` (of ``radarsnn``'s parser).

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="radarsnn")
    >>> _ = add_parsers(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["sweep", "fig7.yaml", "--workers", "2", "--quiet"])
    >>> args.spec, args.workers, args.scheduler, args.quiet, args.json
    ('fig7.yaml', 2, None, True, False)
    """
    p = subparsers.add_parser("sweep", help="run an accuracy-vs-resources sweep on Dask")
    p.add_argument("spec", metavar="SPEC.yaml", help="the sweep file (docs/sweeps.md)")
    p.add_argument("--scheduler", metavar="ADDR",
                   help="address of a running Dask scheduler, or 'sync' to run in this "
                        "process (default: start a LocalCluster)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="LocalCluster worker processes (default 2)")
    p.add_argument("--out", metavar="DIR",
                   help="output folder (default sweeps/<spec name>); re-running resumes it")
    p.add_argument("--max-cells", type=int, metavar="N",
                   help="stop after N new cells (the next run goes on)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.set_defaults(func=run_command, holds_freed_memory=True)
    return p


#: The name the task brief used; the CLI collects ``add_parsers``.
add_parser = add_parsers
