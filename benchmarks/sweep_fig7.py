"""Vogginger et al.'s (2022) Fig. 7 as a sweep: wall time of ``examples/sweeps/fig7.yaml`` on a
LocalCluster.

1 000 simulated CARRADA-like maps (dB) x 8 step counts x {OS, CA} spiking CFAR
against the conventional CFAR (the goal: < 10 minutes on 2 cores).
Runs into a fresh folder (nothing is resumed), prints the sensitivity/precision
table, the wall time, the per-cell CPU seconds and the machine's load average
(the figure is only meaningful on an otherwise idle machine).

Usage::

    python benchmarks/sweep_fig7.py                  # the full sweep, 2 workers
    python benchmarks/sweep_fig7.py --maps 100       # a quick look
    python benchmarks/sweep_fig7.py --workers 1 --out /tmp/fig7-1w
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _cpu_seconds() -> float:
    """User + system CPU of this process and of its finished children (the workers)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def main(argv: list[str] | None = None) -> None:
    """Run the Fig.-7 sweep once and print its figures and timings."""
    from radarsnn.sweep import load_spec, run_sweep
    from radarsnn.sweep.results import RESULTS_FILE, read_records

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", type=int, default=None, help="override n_frames (default 1000)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scheduler", default=None, help="a Dask scheduler address, or 'sync'")
    ap.add_argument("--out", default=None, help="output folder (default: a new temp folder)")
    args = ap.parse_args(argv)
    spec = load_spec(ROOT / "examples" / "sweeps" / "fig7.yaml")
    if args.maps:
        spec = spec.model_copy(update={"frames": spec.frames.model_copy(
            update={"n_frames": args.maps})})
    out = Path(args.out or tempfile.mkdtemp(prefix="fig7-"))
    load0 = os.getloadavg()
    t0, cpu0 = time.perf_counter(), _cpu_seconds()
    result = run_sweep(spec, out, scheduler=args.scheduler, workers=args.workers)
    wall, cpu_all = time.perf_counter() - t0, _cpu_seconds() - cpu0
    load1 = os.getloadavg()
    print(f"\n{'chain':>5} {'steps':>6} {'sensitivity':>12} {'precision':>10} {'Pd':>6} "
          f"{'Pd conv':>7} {'spikes/frame':>12}")
    for row in result.rows:
        p, m, c = row["params"], row["metrics"], row["cost"]
        if row["error"] or not m:
            print(f"{p['chain']:>5} {p['time_steps']:>6} {row['error'] or 'incomplete'}")
            continue
        print(f"{p['chain']:>5} {p['time_steps']:>6} {100 * m['cfar']['sensitivity']:>11.2f}% "
              f"{100 * m['cfar']['precision']:>9.2f}% {m['detection']['pd']:>6.3f} "
              f"{m['detection']['pd_conventional']:>7.3f} {c['spikes_per_frame']:>12.0f}")
    recs = read_records(out / RESULTS_FILE)
    cells_wall = sum(r["seconds"] for r in recs)
    cells_cpu = sum(r.get("cpu_seconds", 0.0) for r in recs)
    print(f"\n{result.n_run} cells run ({result.n_failed} failed) of {result.n_cells}, "
          f"{spec.n_frames()} maps per point, {args.workers} workers on {os.cpu_count()} cores")
    print(f"wall {wall:.0f} s; CPU of this process and its workers {cpu_all:.0f} s "
          f"(/ {args.workers} = {cpu_all / args.workers:.0f} s: the wall time on idle cores)")
    print(f"cell evaluations: {cells_wall:.0f} s wall, {cells_cpu:.0f} s CPU summed over cells "
          "(frames, reference and compile tasks not included)")
    print(f"load average before {load0[0]:.2f}, after {load1[0]:.2f} (1 min)")
    print(f"results: {out}  figures: {[str(p) for p in result.figures]}")


if __name__ == "__main__":
    main()
