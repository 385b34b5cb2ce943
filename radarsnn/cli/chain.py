"""Chain sub-commands: ``validate``, ``schema``, ``compile``, ``report``.

``compile`` turns a chain file into a program artifact directory (see
:mod:`backends.program_artifact`) and checks its accuracy on the calibration data;
``report`` prints what a chain (or a compiled artifact) costs on a target.
``run`` lives in :mod:`radarsnn.cli.run`.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ir.errors import RadarSNNError
from radarsnn.cli.arrays import (
    INPUT_FORMS,
    MAX_NPY_BYTES,
    bin_layout_argument,
    load_arrays,
    read_npy,
)
from radarsnn.cli.usage import UsageError

__all__ = ["MAX_NPY_BYTES", "add_parsers", "compile_chain", "host_fallback_line", "load_arrays",
           "parse_options", "read_npy", "write_output"]


def _cmd_validate(args: argparse.Namespace) -> int:
    """Check every chain file; one line per bad file (naming it), non-zero if any failed."""
    from ir import Graph

    failed = 0
    for path in args.chains:
        try:
            graph = Graph.from_yaml(path)
            graph.verify()
            types = graph.infer_types()
        except (RadarSNNError, OSError) as err:
            if getattr(args, "debug", False):
                raise
            failed += 1
            _validate_error(args, path, err)
            continue
        if args.json:
            print(json.dumps({"chain": str(path), "name": graph.name, "ok": True,
                              "nodes": len(types)}))
            continue
        print(f"{path}: chain {graph.name!r} is valid ({len(types)} nodes)")
        for node_id in graph.topological_order():
            t = types[node_id]
            axes = " × ".join(f"{a}:{n}" for a, n in t.axes.items())
            kind = "complex" if t.complex else "real"
            print(f"  {node_id:<12} {graph.op(node_id).op:<12} [{axes}] {kind} {t.domain}")
    return 1 if failed else 0  # 1: the check failed (the files were read and judged)


def _validate_error(args: argparse.Namespace, path: Path, err: Exception) -> None:
    """One line for a bad chain file: ``error: FILE: …`` on stderr, or a JSON object."""
    message = " ".join(str(err).split())
    if isinstance(err, OSError) and not isinstance(err, RadarSNNError):
        message = f"cannot read the chain file: {err.strerror or err}"
    if not message.startswith(str(path)):  # every line starts with the file it is about
        message = f"{path}: {message}"
    message = " ".join(message.split())  # one line, also for a file name holding newlines
    if args.json:
        print(json.dumps({"chain": str(path), "file": str(path), "ok": False,
                          "error": message, "type": type(err).__name__,
                          "node": getattr(err, "node", None)}, sort_keys=True))
    else:
        print(f"error: {message}", file=sys.stderr)


def _cmd_schema(args: argparse.Namespace) -> int:
    from ir import chain_schema

    text = json.dumps(chain_schema(), indent=2, sort_keys=True)
    if args.output is not None:
        write_output(args.output, (text + "\n").encode("utf-8"), "the schema")
    else:
        print(text)
    return 0


def write_output(path: str | Path, data: bytes, what: str) -> None:
    """Write a command's output file atomically: complete, or not there at all.

    Raises
    ------
    ArtifactError
        ``path`` is no place for a file (a device, a folder, a NUL byte...).
    RadarSNNError
        Naming ``path`` (and the reason, e.g. no space left on the device) when it
        cannot be written; a previous file at ``path`` is kept, no temporary is left.
    """
    from backends.atomic import check_output, write_atomic

    path = check_output(path)  # the name as given: Path() would drop a trailing "/"
    try:
        write_atomic(path, data, durable=True)
    except (OSError, ValueError) as err:  # ValueError: a NUL byte, an empty file name
        reason = getattr(err, "strerror", None) or err
        raise RadarSNNError(f"cannot write {what} to {path}: {reason} (nothing was written; "
                            "free some space or give another path)") from err


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


def _compile(args: argparse.Namespace, target: str | None, *, measured: bool = False):
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


def _cmd_compile(args: argparse.Namespace) -> int:
    from backends import save_program
    from compiler.report.render import totals_line

    program, note = _compile(args, args.target, measured=True)
    folder = save_program(program, args.output, extra={
        "chain_file": str(args.chain), "calibration": note,
        "accuracy": program.records.accuracy.to_dict()})
    report = program.records.report
    totals = report.data["totals"] if report is not None else {}
    segments = [s.kind if s.kind == "spiking" else f"host:{s.node}" for s in program.segments]
    if args.json:
        print(json.dumps({"artifact": str(folder), "chain": program.graph.name,
                          "target": program.target.name, "segments": segments,
                          "totals": totals,
                          "latency": _latency_summary(report),
                          "energy": _energy_summary(report),
                          "accuracy": program.records.accuracy.to_dict(),
                          "host_ops": (program.records.extra.get("motif_selection")
                                       or {}).get("host_ops", [])},
                         sort_keys=True, default=str))
        return 0
    if not args.quiet:
        print(f"compiled chain {program.graph.name!r} for {program.target.name} into {folder}/")
        print(f"  segments: {' → '.join(segments)}")
        if totals:
            print("  " + totals_line(totals))
        if report is not None:
            print("  " + report.latency_line())
            if report.energy_line():
                print("  " + report.energy_line())
        contract = program.records.accuracy
        if hasattr(contract, "lines"):  # measured: the accuracy contract per stage
            print("\n".join(f"  {line}" for line in contract.lines()))
        fallback = host_fallback_line(program.records.extra.get("motif_selection"))
        if fallback:
            print(f"  {fallback}")
        print(f"  {note}; full report: {folder / 'report.md'}")
    return 0


def host_fallback_line(selection: dict | None) -> str | None:
    """The summary's line for ops the search kept on the host (None: every op spiking).

    Examples
    --------
    >>> host_fallback_line({"host_ops": ["cfar"], "chosen": 2, "attempts": [
    ...     {"config": {"cfar": "time"}}, {"config": {"cfar": "time(cfar_steps=300)"}},
    ...     {"config": {"cfar": "host"}}]})
    'on the host: cfar (no spiking configuration kept the contract: time, time(cfar_steps=300))'
    >>> host_fallback_line({"host_ops": [], "attempts": []}) is None
    True
    """
    if not selection or not selection.get("host_ops"):
        return None
    parts = []
    for op in selection["host_ops"]:
        tried = [a["config"][op] for a in selection["attempts"]
                 if a["config"].get(op, "host") != "host"]
        parts.append(f"{op} (no spiking configuration kept the contract: "
                     f"{', '.join(dict.fromkeys(tried))})")
    return "on the host: " + "; ".join(parts)


def _latency_summary(report) -> dict:
    """The real-time fit of ``compile --json``: seconds per frame, frame period, fits."""
    if report is None:
        return {}
    lat = report.data["latency"]
    return {k: lat.get(k) for k in ("total_steps", "total_s", "frame_period_s", "fits",
                                    "max_step_s")}


def _energy_summary(report) -> dict:
    """The energy per frame of ``compile --json``: chip (J), DSP (J), their ratio, basis."""
    energy = report.data.get("energy") if report is not None else None
    if energy is None:
        return {}
    return {k: energy.get(k) for k in ("total_J", "dynamic_J", "static_J", "dsp_J",
                                       "total_to_dsp", "basis")}


def _cmd_report(args: argparse.Namespace) -> int:
    from backends import is_program, load_program
    from radarsnn.cli.notes import artifact_note

    if Path(args.chain).is_dir():
        if not is_program(args.chain):
            raise RadarSNNError(f"{args.chain} is a directory but not a program artifact "
                                "(no program.json); give a chain file or `radarsnn compile` output")
        program, note = load_program(args.chain), artifact_note(args.chain)
        stored = getattr(program.target, "name", None)
        if args.target is not None and args.target != stored:
            raise RadarSNNError(f"{args.chain} was compiled for {stored or 'no target'}; its "
                                f"report is for that target, not {args.target}: report the "
                                f"chain file instead (radarsnn report CHAIN.yaml --target "
                                f"{args.target})")
    else:
        program, note = _compile(args, args.target or "loihi2")
    report = program.records.report
    if report is None:
        raise RadarSNNError(f"{args.chain}: the program was compiled without a target; no report")
    if args.core_map is not None:
        write_output(args.core_map, report.core_map_png(), "the core map")
    if args.format is not None:
        print(f"warning: --format {args.format} is deprecated and will be removed; "
              + ("use --json" if args.format == "json" else "Markdown is the default")
              + " (the same output)", file=sys.stderr)
    if args.format == "json" or args.json:
        print(report.to_json())
        if "synthetic noise" in note:  # stdout stays JSON; the caveat goes to stderr
            print(f"note: {note}", file=sys.stderr)
    else:
        print(report.to_markdown())
        print(f"\n_{note}._")
    return 0


def _motif_help() -> str:
    """The motifs per op, from the registry the compiler uses."""
    from compiler.lowering import default_registry

    described = default_registry().describe()
    return "motifs: " + "; ".join(
        f"{op}: {', '.join(d['motifs'])}" for op, d in sorted(described.items())
        if len(d["motifs"]) > 1)


def _compile_arguments(p: argparse.ArgumentParser) -> None:
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


def add_parsers(sub) -> None:
    """Add ``validate``, ``schema``, ``compile`` and ``report`` to ``sub``."""
    p = sub.add_parser("validate", help="check chain files and print their inferred types; "
                                        "every file is checked, one error line per bad one")
    p.add_argument("chains", nargs="+", type=Path, metavar="CHAIN.yaml",
                   help="one or more chain files to verify")
    p.add_argument("--json", action="store_true",
                   help="one JSON line per chain (a bad one: ok false, file, error, type, node)")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("schema", help="print the JSON schema of chain files")
    p.add_argument("-o", "--output", help="write the schema to this file instead")
    p.set_defaults(func=_cmd_schema)

    p = sub.add_parser("compile", help="compile a chain for a target into an artifact directory")
    _compile_arguments(p)
    p.add_argument("--weight-bits", type=int, help="quantize weights to this many bits")
    p.add_argument("--output", "-o", type=Path, required=True, metavar="DIR",
                   help="the artifact directory to write")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=_cmd_compile)

    p = sub.add_parser("report", help="what a chain (or a compiled artifact) costs on a target")
    _compile_arguments(p)
    p.add_argument("--json", action="store_true",
                   help="print the report as JSON (default: Markdown)")
    p.add_argument("--format", choices=["md", "json"], default=None,
                   help="deprecated: --format json is --json, --format md the default")
    p.add_argument("--core-map", metavar="PNG", help="also draw the core placement map")
    p.set_defaults(func=_cmd_report, target=None)  # None: loihi2, or an artifact's own
