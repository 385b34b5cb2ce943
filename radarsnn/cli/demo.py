"""Demo sub-commands: ``demo`` (scenes, conventional vs spiking, figures) and ``bench``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["add_parsers"]


def _cmd_demo(args: argparse.Namespace) -> int:
    from compiler.progress import make_progress
    from radarsnn.demo import PRESETS, run_demo

    presets = args.preset or list(PRESETS)
    spiking = not args.conventional_only
    out = None if args.no_figures else args.out
    # per preset: scene, 8 compile passes (+ their "done"), compile, simulate
    progress = make_progress(args.quiet or args.json,
                             total=len(presets) * (3 + (11 if spiking else 0)), desc="demo")
    try:
        report = run_demo(seed=args.seed, presets=presets, target=args.target, spiking=spiking,
                          out_dir=out, progress=progress)
    finally:
        getattr(progress, "close", lambda: None)()
    if args.json:
        print(report.to_json())
    else:
        print(report.to_text())
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from compiler.progress import make_progress
    from radarsnn.bench import run_bench

    run_bench = _bench_runner(args, run_bench)
    progress = make_progress(args.quiet or args.json, desc="bench")
    try:
        report = run_bench(args.preset, repeats=args.repeats, step_repeats=args.step_repeats,
                           threads=args.threads, modes=tuple(args.mode or ("closed", "step")),
                           brian2=not args.no_brian2, progress=progress, chain=args.chain,
                           motif=args.motif)
    finally:
        getattr(progress, "close", lambda: None)()
    print(json.dumps(report.to_dict(), indent=2, sort_keys=True) if args.json
          else report.to_text())
    return 0


def _bench_runner(args: argparse.Namespace, run_bench):
    """``run_bench`` with ``user_path`` set from ``--no-user-path``."""
    from functools import partial

    return partial(run_bench, user_path=not args.no_user_path)


def add_parsers(sub) -> None:
    """Add ``demo`` and ``bench`` to ``sub``."""
    from backends.reference.run_options import ENGINE_MODES  # the modes' one home

    p = sub.add_parser("demo", help="simulated scenes through the conventional and spiking chain")
    p.add_argument("--seed", type=int, default=0, help="scene noise seed (default 0)")
    p.add_argument("--preset", action="append", choices=["seed003", "carrada"],
                   help="radar preset(s) to run (default: both)")
    p.add_argument("--target", "-t", default="kapoho_point",
                   help="profile or board of the spiking chain (default kapoho_point: 8 Loihi 2 "
                        "chips; on one loihi2 chip the carrada chain does not fit 10 frames/s)")
    p.add_argument("--out", type=Path, default=Path("radarsnn-demo"), metavar="DIR",
                   help="where figures and summary.md go (default ./radarsnn-demo)")
    p.add_argument("--no-figures", action="store_true", help="write no files")
    p.add_argument("--conventional-only", action="store_true",
                   help="skip the spiking chain (fast: no compilation or simulation)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_demo, holds_freed_memory=True)

    p = sub.add_parser("bench", help="frames/s of the spiking chain vs numpy (and Brian2)")
    p.add_argument("--preset", default="carrada", choices=["seed003", "carrada"],
                   help="radar preset whose scene and chain are timed (default carrada)")
    p.add_argument("--repeats", type=int, default=5, help="timed runs per figure (median)")
    p.add_argument("--step-repeats", type=int, help="timed runs of step mode (default --repeats)")
    p.add_argument("--threads", type=int, default=1, help="BLAS threads (default 1: one core)")
    p.add_argument("--mode", action="append", choices=ENGINE_MODES,
                   help="engines to time (default both)")
    p.add_argument("--no-brian2", action="store_true", help="skip the Brian2 comparison")
    p.add_argument("--no-user-path", action="store_true",
                   help="skip the user's path: run_program as called (one frame, a frames axis "
                        "on 1 and N workers) and compile with and without the accuracy check")
    p.add_argument("--chain", type=Path, metavar="YAML",
                   help="time this chain file instead of the preset's range-Doppler chain "
                        "(its adc input cut from the preset's frames)")
    p.add_argument("--motif", choices=["resonator"],
                   help="time the chain with this DFT motif instead (resonator: loihi2's "
                        "fixed-point resonators; its floor is their rotations)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_bench, holds_freed_memory=True)
