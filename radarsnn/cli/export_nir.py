"""The ``radarsnn export-nir`` sub-command: a chain or a compiled artifact as a NIR file.

``radarsnn export-nir CHAIN_OR_PROGRAM -o OUT.nir [--target T] [-c [NODE=]X.npy]
[--stage NODE]… [--dt-s S]`` (``S`` defaults to the target profile's
``time_step_s``) — a program folder (``radarsnn compile``) or a network
artifact is exported as it is; a chain file is compiled first, like ``radarsnn
report`` (for ``--target``, default ``loihi2``; on ``-c`` inputs or synthetic
noise).  The graph is written with :func:`backends.nir.write_nir`, the export
report (exact / lowered / outside NIR, docs/interop.md) beside it as
``OUT.report.json``.  NIR is an optional extra: without the ``nir`` package the
command fails with one line naming ``pip install 'radarsnn[nir]'``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ir.errors import RadarSNNError

__all__ = ["add_parsers", "export_nir"]

#: What a missing ``nir`` package is told (the extra of pyproject.toml).
NEEDS_NIR = "radarsnn {command} needs the nir package: pip install 'radarsnn[nir]'"


def _require_nir(command: str = "export-nir") -> None:
    """Import ``nir`` or raise a one-line :class:`RadarSNNError` naming ``command``."""
    try:
        import nir  # noqa: F401
    except ImportError:
        raise RadarSNNError(NEEDS_NIR.format(command=command)) from None


def _chain_only(args: argparse.Namespace) -> None:
    """Refuse the compile options for a compiled folder (they would be ignored silently)."""
    given = [flag for flag, value in (("-c/--calibration", args.calibration),
                                      ("-m/--motif", args.motif), ("--option", args.option),
                                      ("--time-steps", args.time_steps),
                                      ("--repetitions", args.repetitions)) if value]
    if given:
        raise RadarSNNError(f"{args.chain} is already compiled: {', '.join(given)} apply to a "
                            "chain file only (export the chain file to compile it again)")


def _profile_step_s(profile) -> float:
    """The profile's ``time_step_s`` (one step of the chip), else 1 s."""
    return float(getattr(profile, "time_step_s", None) or 1.0)


def export_nir(args: argparse.Namespace):
    """Export what ``args`` names to NIR; return ``(path, graph, report, note)``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``export-nir`` command line (``chain``, ``output``, ``target``,
        ``stage``, ``dt_s`` and the compile options of ``radarsnn report``).

    Returns
    -------
    path : Path
        The ``.nir`` file written (the report is ``path.with_suffix(".report.json")``).
    graph : nir.NIRGraph
    report : backends.nir.ExportReport
    note : str
        How the exported program was calibrated.

    Raises
    ------
    RadarSNNError
        ``nir`` is not installed; compile options given with a compiled folder; a
        folder compiled for another ``--target``; ``--stage`` with a network artifact.
    ArtifactError
        No spiking network for the stages, a projection over the dense-weight limit,
        an unreadable artifact, an output path that is no place for a file (a device,
        a folder, a NUL byte), or one that cannot be written (nothing is changed).
    CompileError
        A chain that does not compile (and the other errors of ``radarsnn compile``).
    """
    _require_nir()
    from backends import is_program, load
    from backends.atomic import check_output
    from backends.nir import export_network, export_program, write_nir
    from radarsnn.cli.compiling import compile_from_args  # as `radarsnn compile`/`report`
    from radarsnn.cli.notes import artifact_note

    path = check_output(args.output)  # before any work: a device, a folder, a NUL byte
    check_output(path.with_suffix(".report.json"))
    source = Path(args.chain)
    if source.is_dir():
        _chain_only(args)
        loaded = load(source)
        if not is_program(source):  # one spiking network (backends.save)
            if args.stage:
                raise RadarSNNError(f"{source} is a single-network artifact: --stage selects "
                                    "the networks of a compiled program, drop it")
            from compiler.hardware import load_profile

            dt_s = args.dt_s or _profile_step_s(load_profile(args.target or "loihi2"))
            graph, report = export_network(loaded, dt_s=dt_s)
            note = "a network artifact"
        else:
            stored = getattr(loaded.target, "name", None)
            if args.target is not None and args.target != stored:
                raise RadarSNNError(f"{source} was compiled for {stored or 'no target'}, not "
                                    f"{args.target}: export the chain file instead "
                                    f"(radarsnn export-nir CHAIN.yaml --target {args.target})")
            graph, report = export_program(loaded, stages=args.stage,
                                           dt_s=args.dt_s or _profile_step_s(loaded.target))
            note = artifact_note(source)
    else:
        program, note = compile_from_args(args, args.target or "loihi2")
        graph, report = export_program(program, stages=args.stage,
                                       dt_s=args.dt_s or _profile_step_s(program.target))
    write_nir(graph, report, path)
    return path, graph, report, note


def _cmd_export_nir(args: argparse.Namespace) -> int:
    path, graph, report, note = export_nir(args)
    if args.json:
        print(json.dumps({"nir": str(path), "report": str(path.with_suffix(".report.json")),
                          "nodes": len(graph.nodes), "edges": len(graph.edges),
                          "exact": report.is_exact, "counts": report.to_dict()["counts"],
                          "calibration": note}, sort_keys=True))
    elif not args.quiet:
        print(f"wrote {path} ({len(graph.nodes)} NIR nodes, {len(graph.edges)} edges) and "
              f"{path.with_suffix('.report.json')}; {note}")
        print(report.summary())
    return 0


def add_parsers(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``export-nir`` sub-command to ``subparsers`` (of ``radarsnn``'s parser).

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="radarsnn")
    >>> p = add_parsers(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["export-nir", "chain.yaml", "-o", "out.nir", "--stage", "det"])
    >>> args.output, args.target, args.stage, args.dt_s
    ('out.nir', None, ['det'], None)
    """
    p = subparsers.add_parser("export-nir", help="write a chain's (or a compiled artifact's) "
                                                 "spiking networks as a NIR graph (nir extra)")
    p.add_argument("chain", metavar="CHAIN_OR_PROGRAM",
                   help="a chain YAML file (compiled first) or a `radarsnn compile` folder")
    p.add_argument("--output", "-o", required=True, metavar="OUT.nir",
                   help="the NIR file to write; the export report goes beside it as "
                        "OUT.report.json")
    p.add_argument("--target", "-t", default=None,
                   help="profile a chain is compiled for (default loihi2; a compiled folder "
                        "keeps its own)")
    p.add_argument("--stage", "-s", action="append", metavar="NODE",
                   help="export only the spiking networks of this IR node (repeatable)")
    p.add_argument("--dt-s", type=float, default=None, metavar="SECONDS",
                   help="duration of one step, the dt of the NIR time constants (default: the "
                        "target profile's time_step_s, 1e-05 for loihi2; 1 without one)")
    p.add_argument("--calibration", "-c", action="append", metavar="[NODE=]X.npy",
                   help="calibration input per input node of a chain (default: seeded "
                        "synthetic noise, see docs/cli.md)")
    p.add_argument("--motif", "-m", action="append", metavar="NODE_OR_OP=MOTIF",
                   help="motif choice of a chain, e.g. dft=time-fft (repeatable)")
    p.add_argument("--time-steps", type=int, help="override the per-motif time window")
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="compile option of a chain (docs/compiler.md), VALUE read as YAML")
    p.add_argument("--repetitions", choices=["auto", "spatial", "temporal"],
                   help="repeated stages of a chain (as for radarsnn compile)")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing")
    p.set_defaults(func=_cmd_export_nir)
    return p
