"""Compile a chain file as every command that compiles one does (compile, report, emit, nir).

:func:`compile_chain` reads the chain, checks its cost, reads or draws the calibration
inputs and compiles; :func:`compile_from_args` does it from a parsed command line
(:func:`add_compile_arguments` adds the options: ``--target``, ``-c``, ``-m``,
``--option`` …) and warns on the accuracy it measures; :func:`parse_options` reads the
``KEY=VALUE`` compile options.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ir.errors import RadarSNNError
from radarsnn.cli.arrays import INPUT_FORMS, bin_layout_argument, load_arrays
from radarsnn.cli.usage import UsageError

__all__ = ["add_compile_arguments", "compile_chain", "compile_from_args", "parse_options"]


def parse_options(items: list[str] | None) -> dict:
    """``KEY=VALUE`` compile options, each VALUE read as YAML (``headroom=1.5``, ``x=[1,2]``).

    Examples
    --------
    >>> parse_options(["headroom=1.5", "cfar_ties=exact", "fft_radices=[4, 4]"])
    {'headroom': 1.5, 'cfar_ties': 'exact', 'fft_radices': [4, 4]}

    YAML 1.1's boolean words stay words (no option is a boolean; ``resonator_renorm=off``
    means ``'off'``):

    >>> parse_options(["resonator_renorm=off", "x=true"])
    {'resonator_renorm': 'off', 'x': True}
    """
    import yaml

    from ir.model import short_repr
    from ir.parsing import load_yaml

    options = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise UsageError(f"option {short_repr(item)} is not KEY=VALUE (e.g. headroom=1.5)")
        try:
            options[key] = load_yaml(value, error=RadarSNNError)
            if isinstance(options[key], bool) and value.strip().lower() not in ("true", "false"):
                options[key] = value.strip()  # on/off/yes/no: the word the user wrote
        except yaml.YAMLError as err:
            from ir.serialize import describe_yaml_error

            raise UsageError(f"option {short_repr(key)}: value {short_repr(value)} is not "
                                f"YAML ({describe_yaml_error(err)})") from None
        except RadarSNNError as err:
            raise RadarSNNError(f"option {short_repr(key)}: {err}") from None
    return options


def compile_chain(chain: str | Path, target: str | None, *,
                  calibration: list[str] | None = None, bin_layout: str | None = None,
                  motifs: dict[str, str] | None = None, time_steps: int | None = None,
                  weight_bits: int | None = None, options: dict | None = None,
                  quiet: bool = True, accuracy: str = "off"):
    """Compile a chain file as every command that compiles one does (compile, report, emit, nir).

    Reads the chain, checks its estimated cost before the calibration arrays are read or
    drawn (they are part of the estimate), reads ``calibration`` (``[NODE=]FILE`` items) or
    draws seeded synthetic noise, and compiles with a progress bar unless ``quiet``.

    Returns
    -------
    (CompiledProgram, str, dict)
        The program, its calibration note (:mod:`radarsnn.cli.notes`) and the
        calibration inputs it was compiled on.
    """
    from compiler.calibration import synthetic_inputs
    from compiler.compile import compile_graph, default_pipeline
    from compiler.compile_guards import check_compile, limits_from_options
    from compiler.progress import make_progress
    from ir import Graph
    from radarsnn.cli.notes import GIVEN_NOTE, SYNTHETIC_NOTE

    graph = Graph.from_yaml(chain)
    options = dict(options or {})
    max_memory_bytes, max_time_s = limits_from_options(options)
    # before the calibration arrays are read or drawn: they are part of the estimate
    check_compile(graph, max_memory_bytes=max_memory_bytes, max_time_s=max_time_s)
    if calibration:
        types = graph.infer_types()
        inputs = load_arrays(calibration, graph.input_ids(), f"chain {chain}",
                             bin_layout=bin_layout,
                             shapes={port: types[port].shape for port in graph.input_ids()})
        note = GIVEN_NOTE
    else:  # the counts that depend on it: radarsnn.cli.notes
        inputs = synthetic_inputs(graph, seed=0)
        note = SYNTHETIC_NOTE
    n_passes = len(default_pipeline(options, hardware=target is not None))
    progress = make_progress(quiet, total=n_passes, desc="compile")
    measured = {}
    if accuracy != "off":  # the contract on held-back frames, motifs="auto" (docs/accuracy.md)
        from backends.reference import ReferenceSimulator
        measured = {"simulator": ReferenceSimulator(), "accuracy": accuracy}
    try:
        program = compile_graph(graph, target=target, motifs=motifs or {},
                                calibration_inputs=inputs, time_steps=time_steps,
                                weight_bits=weight_bits, progress=progress, options=options,
                                **measured)
    finally:
        getattr(progress, "close", lambda: None)()
    return program, note, inputs


def compile_from_args(args: argparse.Namespace, target: str | None, *, measured: bool = False):
    """Compile ``args.chain`` as the ``compile`` and ``report`` commands do; (program, note).

    ``measured``: without ``--accuracy``, measure the accuracy contract when calibration
    data is given (``compile``); ``report`` and ``export-nir`` compile unmeasured unless
    ``--accuracy`` asks."""
    options = parse_options(getattr(args, "option", None))
    motifs = {}
    for m in args.motif or []:
        key, sep, value = m.partition("=")
        if not sep:
            raise UsageError(f"--motif {m!r} is not NODE_OR_OP=MOTIF (e.g. dft=time-fft)")
        motifs[key] = value
    if getattr(args, "repetitions", None):
        options["repetitions"] = args.repetitions
    accuracy = getattr(args, "accuracy", None) or (
        "error" if measured and args.calibration else "off")
    program, note, inputs = compile_chain(args.chain, target, calibration=args.calibration,
                                          bin_layout=getattr(args, "bin_layout", None),
                                          motifs=motifs, time_steps=args.time_steps,
                                          weight_bits=getattr(args, "weight_bits", None),
                                          options=options, quiet=args.quiet or args.json,
                                          accuracy=accuracy)
    if accuracy == "off":
        _warn_accuracy(program, inputs, note)
    elif not program.records.accuracy.holds:  # accuracy='warn' kept a failing configuration
        for stage, why in program.records.accuracy.failing():
            print(f"warning: stage {stage.node!r} ({stage.motif}) breaks the accuracy "
                  f"contract: {'; '.join(why)} (accepted: --accuracy warn)", file=sys.stderr)
    return program, note


def _warn_accuracy(program, calibration: dict, note: str) -> None:
    """Measure the spiking segments against the conventional chain on the calibration data.

    Prints one ``warning:`` line on stderr per node whose error is large
    (:mod:`backends.reference.accuracy`) and keeps the figures in
    ``program.records["accuracy"]`` (saved in the artifact's ``extra``).
    """
    from backends.reference.accuracy import check_accuracy
    from radarsnn.cli.notes import GIVEN_NOTE

    check = check_accuracy(program, calibration)
    program.records.accuracy = check
    data = "the calibration data" if note == GIVEN_NOTE else "the synthetic calibration noise"
    if check.skipped:
        print(f"note: the accuracy check was skipped ({check.skipped})", file=sys.stderr)
    for line in check.warnings():
        print(f"warning: {line} on {data} ({check.n_frames} frame(s)); another motif "
              "(--motif NODE=MOTIF), more --time-steps or an exact target may keep it "
              "(radarsnn report CHAIN -m ... compares; docs/fourier.md)", file=sys.stderr)


def _motif_help() -> str:
    """The motifs per op, from the registry the compiler uses."""
    from compiler.lowering import default_registry

    described = default_registry().describe()
    return "motifs: " + "; ".join(
        f"{op}: {', '.join(d['motifs'])}" for op, d in sorted(described.items())
        if len(d["motifs"]) > 1)


def add_compile_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("chain", type=Path, metavar="CHAIN.yaml",
                   help="the chain file to compile (report: or a `radarsnn compile` artifact "
                        "directory)")
    p.add_argument("--target", "-t", default="loihi2",
                   help="built-in profile (loihi, loihi2, spinnaker2, unbounded) or a YAML file "
                        "(default loihi2)")
    p.add_argument("--calibration", "-c", action="append", metavar="[NODE=]FILE",
                   help=f"calibration input per input node: {INPUT_FORMS} (default: seeded "
                        "synthetic noise in each input's domain)")
    bin_layout_argument(p)
    p.add_argument("--motif", "-m", action="append", metavar="NODE_OR_OP=MOTIF",
                   help="motif choice, e.g. dft=time-fft or mag=host (repeatable); "
                        + _motif_help())
    p.add_argument("--time-steps", type=int, help="override the per-motif time window")
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="compile option (see docs/compiler.md), VALUE read as YAML")
    p.add_argument("--repetitions", choices=["auto", "spatial", "temporal"],
                   help="repeated stages: unrolled (spatial), one instance run R times per "
                        "frame (temporal), or spatial where it fits (auto, default)")
    p.add_argument("--accuracy", choices=["error", "warn", "off"],
                   help="measure every spiking stage on held-back calibration frames and "
                        "choose the motifs that keep the conventional chain's detections "
                        "(docs/accuracy.md): refuse a chain that loses them (error: compile's "
                        "default with -c), keep the best and warn (warn), or skip it (off: "
                        "the default on synthetic noise and of report)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
