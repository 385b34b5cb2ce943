"""The ``run`` sub-command: simulate a compiled program or network artifact on inputs.

Inputs are read by :mod:`radarsnn.cli.arrays` (``.npy``, ``.npz``, ``.mat``, TI
``.bin``); one with a leading frames axis runs frame after frame with a progress
bar (:mod:`ir.frames`), the frames shared out to ``--workers`` workers (default: one
per available core) of the ``--parallel`` kind (default ``auto``: worker processes where the
system can fork, :mod:`backends.reference.frames_pool`).  Values above an encoder's
calibrated range are refused by default (one ``error:`` line naming the count and
``--clip``); ``--clip`` clips them silently, ``--out-of-range warn`` clips them with one
warning line (docs/cli.md).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from radarsnn.cli.arrays import INPUT_FORMS, bin_layout_argument, load_arrays
from radarsnn.cli.chain import write_output

__all__ = ["add_parsers", "clipped_warning"]


def _cmd_run(args: argparse.Namespace) -> int:
    import numpy as np

    from backends import is_program, load
    from backends.atomic import check_output

    _refuse_a_file(args.artifact)
    path = None
    if args.output is not None:  # before any work: a device (/dev/null), a folder, a NUL byte
        given = str(args.output)
        if given.endswith(("/", os.sep)) or not os.path.isdir(given):  # `-o out` beside a
            check_output(given)  # folder `out` writes out.npz; no /dev/null.npz beside a device
        path = check_output(given if given.endswith(".npz") else f"{given}.npz")
    loaded = load(args.artifact)
    if is_program(args.artifact):
        ports = loaded.graph.input_ids()
        types = loaded.graph.infer_types()
        shapes = {port: types[port].shape for port in ports}
    else:
        from backends.reference.encoding import value_shape

        ports = [e.port for e in loaded.encoders]
        shapes = {port: value_shape(loaded, port) for port in ports}
    inputs = load_arrays(args.input, ports, f"artifact {args.artifact}",
                         bin_layout=args.bin_layout, shapes=shapes)
    policy = "clip" if args.clip else args.out_of_range
    result = _simulate_frames(loaded, inputs, args, "reject" if policy == "reject" else "clip")
    if policy == "warn" and result.clipped:
        print(clipped_warning(result.clipped), file=sys.stderr)
    if path is not None:
        from backends.artifact_io import npz_bytes

        write_output(path, npz_bytes({k: np.asarray(v) for k, v in result.outputs.items()}),
                     "the outputs")
    if args.json:
        print(json.dumps({"mode": result.mode, "spikes": result.total_spikes,
                          "synaptic_events": result.total_synaptic_events,
                          "spike_counts": result.spike_counts, "clipped": result.clipped,
                          "state_overflow": result.state_overflow,
                          "outputs": {k: list(np.shape(v)) for k, v in result.outputs.items()}},
                         sort_keys=True))
    elif not args.quiet:
        print(result.summary())
    return 0


def _refuse_a_file(path: Path) -> None:
    """``run`` takes a compiled artifact directory: say what to do with a chain or other file.

    Examples
    --------
    >>> _refuse_a_file(Path("examples/chains/ti_range.yaml"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ir.errors.ArtifactError: examples/chains/ti_range.yaml is a chain file, ...: compile it ...
    """
    from ir.errors import ArtifactError

    if not path.is_file():
        return
    if path.name in ("program.json", "manifest.json"):
        raise ArtifactError(f"{path} is a file of an artifact: give its directory "
                            f"(radarsnn run {path.parent} -i …)")
    if path.suffix.lower() in (".yaml", ".yml", ".json"):
        raise ArtifactError(f"{path} is a chain file, not a compiled artifact: compile it first "
                            f"(radarsnn compile {path} -o DIR), then run the directory "
                            "(radarsnn run DIR -i …)")
    raise ArtifactError(f"{path} is a file, not a compiled artifact directory: give the "
                        "directory `radarsnn compile CHAIN.yaml -o DIR` wrote")


def _simulate_frames(loaded, inputs: dict, args: argparse.Namespace, out_of_range: str):
    """Run a program (frame by frame, with a progress bar when there are frames) or a network."""
    from backends.reference import run_program, simulate
    from compiler.program import CompiledProgram
    from ir.frames import n_frames

    if not isinstance(loaded, CompiledProgram):  # a network: simulate batches the frames
        return simulate(loaded, inputs, mode=args.mode, out_of_range=out_of_range)
    types = loaded.graph.infer_types()
    count = n_frames(types, inputs, f"program {loaded.graph.name!r}")
    if count is None or args.quiet or args.json:
        return run_program(loaded, inputs, mode=args.mode, out_of_range=out_of_range,
                           workers=args.workers, parallel=args.parallel)
    from compiler.progress import bar_without_thread

    with bar_without_thread(total=count, desc="run", unit="frame", file=sys.stderr,
                            leave=False, disable=None,  # None: no bar off a terminal
                            dynamic_ncols=True) as bar:
        return run_program(loaded, inputs, mode=args.mode, out_of_range=out_of_range,
                           progress=lambda done, total: bar.update(1), workers=args.workers,
                           parallel=args.parallel)


def _workers(text: str) -> int:
    """``--workers N``: a whole number >= 1 (argparse names the flag when it is not).

    Examples
    --------
    >>> _workers("2")
    2
    >>> _workers("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: 0 is not a whole number >= 1
    """
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text} is not a whole number >= 1")
    return value


def clipped_warning(clipped: dict[str, int]) -> str:
    """The ``warning:`` line of ``radarsnn run --out-of-range warn`` when it clipped inputs.

    Examples
    --------
    >>> print(clipped_warning({"adc": 12}))  # doctest: +NORMALIZE_WHITESPACE
    warning: clipped to the calibrated encoder range: 12 value(s) at 'adc' (stronger than
    the calibration data; the strongest returns saturate). To keep them: compile with -c on
    data that covers them or --option headroom=2; to refuse them: --out-of-range reject
    """
    where = ", ".join(f"{n} value(s) at {port!r}" for port, n in sorted(clipped.items()))
    return (f"warning: clipped to the calibrated encoder range: {where} (stronger than the "
            "calibration data; the strongest returns saturate). To keep them: compile with -c "
            "on data that covers them or --option headroom=2; to refuse them: "
            "--out-of-range reject")


def add_parsers(sub) -> None:
    """Add ``run`` to ``sub``."""
    from backends.reference.run_options import MODES  # the modes' one home (numpy: only here)

    p = sub.add_parser("run", help="simulate a compiled artifact on inputs (.npy, .npz, .mat, "
                                   "TI .bin)")
    p.add_argument("artifact", type=Path, metavar="ARTIFACT_DIR",
                   help="a compiled artifact directory (`radarsnn compile CHAIN.yaml -o DIR`); "
                        "a chain file must be compiled first")
    p.add_argument("--input", "-i", action="append", required=True, metavar="[PORT=]FILE",
                   help=f"input array per port, each port once: {INPUT_FORMS} (repeat for "
                        "several ports)")
    bin_layout_argument(p)
    p.add_argument("--mode", choices=MODES, default="auto",
                   help="simulation engine: step (every time step), closed (the spike steps "
                        "of a fire-once feed-forward network computed directly), auto (closed "
                        "for a network that is eligible, else step; the default)")
    p.add_argument("--out-of-range", choices=["reject", "warn", "clip"], default="reject",
                   help="input values above an encoder's calibrated range (a scene stronger "
                        "than the calibration data): refuse them with an error naming the "
                        "count (reject, the default), clip them and print one warning line "
                        "with the count (warn), or clip silently (clip); a clipped count is in "
                        "the summary and --json")
    p.add_argument("--clip", action="store_true", help="the same as --out-of-range clip")
    p.add_argument("--workers", type=_workers, default=None, metavar="N",
                   help="workers that share out the frames of an input with a frames axis "
                        "(the result is the same for any N; default: one per available core)")
    p.add_argument("--parallel", choices=["auto", "threads", "processes"], default="auto",
                   help="what the workers are: threads, or worker processes forked once "
                        "(auto, the default: processes where the system can fork, else "
                        "threads; the result is the same)")
    p.add_argument("--output", "-o", help="write decoded outputs to this .npz")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing")
    p.set_defaults(func=_cmd_run, holds_freed_memory=True)
