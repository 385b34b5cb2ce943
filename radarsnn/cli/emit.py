"""The ``radarsnn emit`` sub-command: a chain or an artifact as a generated simulator package.

``radarsnn emit ARTIFACT_OR_CHAIN --target T --backend numpy -o OUT_DIR`` —
an artifact directory is emitted as it is; a chain file (YAML) is compiled
first for ``--target``, calibrated on ``--calibration [NODE=]X.npy`` or, like
``radarsnn report``, on synthetic noise.  :func:`add_parsers` registers the
sub-command on an ``argparse`` sub-parsers object; :func:`run_emit` does the work.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from backends.emit import EMITTERS
from ir.errors import CompileError
from radarsnn.cli.compiling import compile_chain

__all__ = ["add_parsers", "run_emit"]


def run_emit(source: str | Path, out_dir: str | Path, *, target: str = "loihi2",
             backend: str = "numpy", calibration: list[str] | None = None,
             name: str | None = None, time_steps: int | None = None) -> Path:
    """Emit the generated simulator of an artifact directory or a chain file.

    Parameters
    ----------
    source : str or Path
        An artifact directory (``backends.artifact.save``) or a chain YAML file.
    out_dir : str or Path
        Where the package folder is written.
    target : str
        Hardware profile a chain is compiled for (ignored for an artifact).
    backend : str
        A key of :data:`backends.emit.EMITTERS` (``numpy``).
    calibration : list of str, optional
        ``[NODE=]X.npy`` calibration inputs of a chain (default: synthetic noise).
    name : str, optional
        Package name (default from the chain name).
    time_steps : int, optional
        Override the per-motif time window of a chain.

    Returns
    -------
    Path
        The package directory.

    Raises
    ------
    CompileError
        An unknown backend, or a chain that does not compile.
    RadarSNNError
        Unreadable inputs (more specific subclasses for chain and artifact errors).
    """
    if backend not in EMITTERS:
        raise CompileError(f"backend {backend!r} has no emitter; known: {sorted(EMITTERS)}")
    path = Path(source)
    if path.is_dir():
        return EMITTERS[backend](path, out_dir, name=name)
    program, _note, _inputs = compile_chain(path, target, calibration=calibration,
                                            time_steps=time_steps)  # as compile and report do
    return EMITTERS[backend](program, out_dir, name=name)


def _cmd_emit(args: argparse.Namespace) -> int:
    folder = run_emit(args.source, args.output, target=args.target, backend=args.backend,
                      calibration=args.calibration, name=args.name, time_steps=args.time_steps)
    print(folder)
    return 0


def add_parsers(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``emit`` sub-command to ``subparsers`` (of ``radarsnn``'s parser).

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="radarsnn")
    >>> p = add_parsers(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["emit", "chain.yaml", "-o", "out"])
    >>> args.backend, args.target, args.output
    ('numpy', 'loihi2', 'out')
    """
    p = subparsers.add_parser("emit", help="generate a standalone simulator package (numpy)")
    p.add_argument("source", metavar="ARTIFACT_OR_CHAIN",
                   help="an artifact directory or a chain YAML file (compiled first)")
    p.add_argument("--target", "-t", default="loihi2",
                   help="hardware profile a chain is compiled for (default loihi2)")
    p.add_argument("--backend", "-b", default="numpy", choices=sorted(EMITTERS),
                   help="what to generate (numpy: a standalone numpy simulator package)")
    p.add_argument("--output", "-o", required=True, metavar="OUT_DIR",
                   help="directory that receives the package folder")
    p.add_argument("--name", help="package name (default: snn_<chain>)")
    p.add_argument("--calibration", "-c", action="append", metavar="[NODE=]X.npy",
                   help="calibration input per input node (default: seeded synthetic noise "
                        "in each input's domain)")
    p.add_argument("--time-steps", type=int, help="override the per-motif time window")
    p.set_defaults(func=_cmd_emit)
    return p
