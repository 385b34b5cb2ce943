"""Chain sub-commands: ``validate``, ``schema``, ``compile``, ``report``.

``compile`` turns a chain file into a program artifact directory (see
:mod:`backends.program_artifact`) and checks its accuracy on the calibration data;
``report`` prints what a chain (or a compiled artifact) costs on a target; both compile
through :mod:`radarsnn.cli.compiling`.  ``run`` lives in :mod:`radarsnn.cli.run`.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ir.errors import RadarSNNError
from radarsnn.cli.arrays import MAX_NPY_BYTES, load_arrays, read_npy
from radarsnn.cli.compiling import add_compile_arguments, compile_from_args

__all__ = ["MAX_NPY_BYTES", "add_parsers", "host_fallback_line", "load_arrays", "read_npy",
           "write_output"]


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


def _cmd_compile(args: argparse.Namespace) -> int:
    from backends import save_program
    from compiler.report.render import totals_line

    program, note = compile_from_args(args, args.target, measured=True)
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
        program, note = compile_from_args(args, args.target or "loihi2")
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
    add_compile_arguments(p)
    p.add_argument("--weight-bits", type=int, help="quantize weights to this many bits")
    p.add_argument("--output", "-o", type=Path, required=True, metavar="DIR",
                   help="the artifact directory to write")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=_cmd_compile)

    p = sub.add_parser("report", help="what a chain (or a compiled artifact) costs on a target")
    add_compile_arguments(p)
    p.add_argument("--json", action="store_true",
                   help="print the report as JSON (default: Markdown)")
    p.add_argument("--format", choices=["md", "json"], default=None,
                   help="deprecated: --format json is --json, --format md the default")
    p.add_argument("--core-map", metavar="PNG", help="also draw the core placement map")
    p.set_defaults(func=_cmd_report, target=None)  # None: loihi2, or an artifact's own
