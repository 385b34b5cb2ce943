"""The ``run`` sub-command: simulate a compiled program or network artifact on inputs.

Inputs are read by :mod:`compiler.cli.arrays` (``.npy``, ``.npz``, ``.mat``, TI
``.bin``); one with a leading frames axis runs frame after frame with a progress
bar (:mod:`ir.frames`).  Values above an encoder's calibrated range are clipped
with one warning line by default (``--out-of-range``, docs/cli.md).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from compiler.cli.arrays import INPUT_FORMS, bin_layout_argument, load_arrays
from compiler.cli.chain import write_output

__all__ = ["add_parsers", "clipped_warning"]


def _cmd_run(args: argparse.Namespace) -> int:
    import numpy as np

    from backends import is_program, load

    loaded = load(args.artifact)
    if is_program(args.artifact):
        ports = loaded.graph.input_ids()
    else:
        ports = [e.port for e in loaded.encoders]
    inputs = load_arrays(args.input, ports, f"artifact {args.artifact}",
                         bin_layout=args.bin_layout)
    policy = "clip" if args.clip else args.out_of_range
    result = _simulate_frames(loaded, inputs, args, "reject" if policy == "reject" else "clip")
    if policy == "warn" and result.clipped:
        print(clipped_warning(result.clipped), file=sys.stderr)
    if args.output:
        from backends.artifact_io import npz_bytes

        path = args.output if str(args.output).endswith(".npz") else f"{args.output}.npz"
        write_output(path, npz_bytes({k: np.asarray(v) for k, v in result.outputs.items()}),
                     "the outputs")
    if args.json:
        print(json.dumps({"mode": result.mode, "spikes": result.total_spikes,
                          "synaptic_events": result.total_synaptic_events,
                          "spike_counts": result.spike_counts, "clipped": result.clipped,
                          "outputs": {k: list(np.shape(v)) for k, v in result.outputs.items()}},
                         sort_keys=True))
    elif not args.quiet:
        print(result.summary())
    return 0


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
        return run_program(loaded, inputs, mode=args.mode, out_of_range=out_of_range)
    from tqdm import tqdm

    with tqdm(total=count, desc="run", unit="frame", file=sys.stderr, leave=False,
              disable=None, dynamic_ncols=True) as bar:  # disable=None: no bar off a terminal
        return run_program(loaded, inputs, mode=args.mode, out_of_range=out_of_range,
                           progress=lambda done, total: bar.update(1))


def clipped_warning(clipped: dict[str, int]) -> str:
    """The ``warning:`` line of ``radarsnn run`` when it clipped inputs (``--out-of-range warn``).

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
    p = sub.add_parser("run", help="simulate a compiled artifact on inputs (.npy, .npz, .mat, "
                                   "TI .bin)")
    p.add_argument("artifact", type=Path, metavar="ARTIFACT_DIR")
    p.add_argument("--input", "-i", action="append", required=True, metavar="[PORT=]FILE",
                   help=f"input array per port, each port once: {INPUT_FORMS} (repeat for "
                        "several ports)")
    bin_layout_argument(p)
    p.add_argument("--mode", choices=["step", "closed", "auto"], default="auto")
    p.add_argument("--out-of-range", choices=["warn", "clip", "reject"], default="warn",
                   help="input values above an encoder's calibrated range (a scene stronger "
                        "than the calibration data): clip them and print one warning line with "
                        "the count (warn, the default), clip silently (clip), or refuse them "
                        "with an error (reject); the count is in the summary and --json")
    p.add_argument("--clip", action="store_true", help="the same as --out-of-range clip")
    p.add_argument("--output", "-o", help="write decoded outputs to this .npz")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing")
    p.set_defaults(func=_cmd_run)
