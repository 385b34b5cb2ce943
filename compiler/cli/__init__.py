"""The ``radarsnn`` command line.

Sub-commands live in small modules, each with an ``add_parsers(subparsers)``
function, collected explicitly in :data:`COMMAND_MODULES`:

* :mod:`compiler.cli.chain` — ``validate``, ``schema``, ``compile``, ``report``, ``run``;
* :mod:`compiler.cli.demo` — ``demo``, ``bench``;
* :mod:`backends.emit.command` — ``emit``; :mod:`compiler.sweep.command` — ``sweep``
  (Dask is imported only when a sweep runs).

Errors from the project's hierarchy (and unreadable files) are printed as one
line ``error: …`` on stderr with exit status 2 — as a JSON object on stdout
with ``--json`` — and no traceback unless ``--debug`` is given.

Examples
--------
>>> main(["schema"]) == 0  # doctest: +ELLIPSIS
{...
True
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from importlib import import_module

from ir.errors import RadarSNNError

__all__ = ["COMMAND_MODULES", "build_parser", "main"]

#: Modules whose ``add_parsers(subparsers)`` add the sub-commands, in help order.
COMMAND_MODULES = ("compiler.cli.chain", "compiler.cli.demo", "backends.emit.command",
                   "compiler.sweep.command")


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("radarsnn")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


class UsageError(Exception):
    """A bad command line (argparse's complaint), reported like every other error."""


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (``error: …``), not usage text and exit."""

    def error(self, message: str):  # argparse's hook; also used by the sub-parsers
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``radarsnn`` command."""
    parser = _Parser(
        prog="radarsnn",
        description="Compile automotive-radar DSP chains into spiking neural networks.")
    parser.add_argument("--version", action="version", version=f"radarsnn {_version()}")
    parser.add_argument("--debug", action="store_true",
                        help="show the full traceback of an error")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        import_module(name).add_parsers(sub)
    for command in sub.choices.values():  # also after the command: radarsnn run ... --debug
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show the full traceback of an error")
    return parser


def _error_exit(err: BaseException, args: argparse.Namespace | None) -> int:
    message = " ".join(str(err).split())  # one line, whatever a library put in the message
    if isinstance(err, OSError) and not isinstance(err, RadarSNNError):
        message = f"{err.strerror or err}: {err.filename}" if err.filename else str(err)
    if args is not None and getattr(args, "json", False):
        print(json.dumps({"error": message, "type": type(err).__name__,
                          "node": getattr(err, "node", None)}, sort_keys=True))
    else:
        print(f"error: {message}", file=sys.stderr)
    return 2


def _silence_stdout() -> None:
    """Point stdout at the null device, so the interpreter's final flush cannot fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # not a file descriptor (a test's capture)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 on an error, 1 on a failed check)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser().parse_args(argv)
    except UsageError as err:
        return _error_exit(err, argparse.Namespace(json="--json" in argv))
    try:
        return args.func(args)
    except BrokenPipeError:  # the reader stopped (`radarsnn schema | head`): it had its output
        _silence_stdout()
        return 0
    except (RadarSNNError, OSError) as err:
        if args.debug:
            raise
        return _error_exit(err, args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
