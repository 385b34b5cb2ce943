"""The ``radarsnn`` command line.

Sub-commands live in small modules of this package, each with an
``add_parsers(subparsers)`` function; :data:`COMMANDS` maps each sub-command to the
function that imports its module:

* :mod:`radarsnn.cli.chain` — ``validate``, ``schema``, ``compile``, ``report``;
* :mod:`radarsnn.cli.run` — ``run``; :mod:`radarsnn.cli.export_nir` — ``export-nir``;
  :mod:`radarsnn.cli.import_nir` — ``import-nir``;
* :mod:`radarsnn.cli.demo` — ``demo``, ``bench``;
* :mod:`radarsnn.cli.emit` — ``emit``; :mod:`radarsnn.cli.sweep` — ``sweep``
  (Dask is imported only when a sweep runs);
* :mod:`radarsnn.cli.crosscheck` — ``crosscheck``.

Exit status (:data:`EXIT_OK`, :data:`EXIT_ERROR`, :data:`EXIT_USAGE`): 0 on success;
1 on a runtime error — an error of the project's hierarchy, an unreadable file, or a
check that failed (``validate``); 2 on a usage error (a bad command line, argparse's
convention).  Either error is printed as one line ``error: …`` on stderr — a JSON
object on stdout with ``--json`` — and no traceback unless ``--debug`` is given.

A Python warning raised while a command runs (a ``ResonatorDriftWarning``, an
``OutOfRangeWarning`` …) is printed as one line ``warning: …`` on stderr, not as
Python's two-line ``file:line: Category: …`` form.

Diagnostics go through :mod:`logging`, one logger per package (``ir``, ``radar``,
``compiler``, ``backends``, named by module); ``-v`` shows their INFO records on
stderr (what each pass did and how long it took), ``-vv`` DEBUG.  Without ``-v``
only warnings are shown.

Examples
--------
>>> main(["schema"]) == 0  # doctest: +ELLIPSIS
{...
True
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from types import ModuleType

from ir.errors import RadarSNNError
from radarsnn.cli.usage import UsageError

__all__ = ["COMMANDS", "EXIT_ERROR", "EXIT_OK", "EXIT_USAGE",
           "LOGGED_PACKAGES", "build_parser", "configure_logging", "main", "show_warning"]

#: Exit status of a command that did its work.
EXIT_OK = 0
#: Exit status of a runtime error (a typed error, an unreadable file, a failed check).
EXIT_ERROR = 1
#: Exit status of a usage error (a bad command line).
EXIT_USAGE = 2
#: The first-party packages whose loggers ``-v`` shows.
LOGGED_PACKAGES = ("ir", "radar", "compiler", "backends")


# One function per command module: a normal import, made when a command needs it.
def _chain() -> ModuleType:
    from radarsnn.cli import chain
    return chain


def _run() -> ModuleType:
    from radarsnn.cli import run
    return run


def _demo() -> ModuleType:
    from radarsnn.cli import demo
    return demo


def _emit() -> ModuleType:
    from radarsnn.cli import emit
    return emit


def _sweep() -> ModuleType:
    from radarsnn.cli import sweep
    return sweep


def _export_nir() -> ModuleType:
    from radarsnn.cli import export_nir
    return export_nir


def _import_nir() -> ModuleType:
    from radarsnn.cli import import_nir
    return import_nir


def _crosscheck() -> ModuleType:
    from radarsnn.cli import crosscheck
    return crosscheck


#: Sub-command -> the function importing the module whose ``add_parsers`` adds it, in help
#: order.  :func:`main` imports only the module of the command it runs (none for
#: ``--version``), so a command does not pay for the others' imports (Dask, the emitter,
#: …); a command missing here makes it import them all.
COMMANDS: dict[str, Callable[[], ModuleType]] = {
    "validate": _chain, "schema": _chain, "compile": _chain, "report": _chain, "run": _run,
    "demo": _demo, "bench": _demo, "emit": _emit, "sweep": _sweep,
    "export-nir": _export_nir, "import-nir": _import_nir, "crosscheck": _crosscheck}


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("radarsnn")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (``error: …``), not usage text and exit."""

    def error(self, message: str):  # argparse's hook; also used by the sub-parsers
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")


def build_parser(modules: Sequence[ModuleType] | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``radarsnn`` command.

    Parameters
    ----------
    modules : sequence of module, optional
        The modules whose sub-commands to add (default: every module of :data:`COMMANDS`).

    Examples
    --------
    >>> parser = build_parser([_run()])
    >>> parser.parse_args(["run", "DIR", "-i", "x.npy"]).command
    'run'
    """
    parser = _Parser(
        prog="radarsnn",
        description="Compile automotive-radar DSP chains into spiking neural networks.")
    parser.add_argument("--version", action="version", version=f"radarsnn {_version()}")
    parser.add_argument("--debug", action="store_true",
                        help="show the full traceback of an error")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log what the compiler and simulator do (-v: info, -vv: debug)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                help="the sub-command (radarsnn COMMAND --help for its options)")
    if modules is None:
        modules = [load() for load in dict.fromkeys(COMMANDS.values())]
    for module in modules:
        module.add_parsers(sub)
    for command in sub.choices.values():  # also after the command: radarsnn run ... --debug
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show the full traceback of an error")
        command.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                             help="log what the compiler and simulator do (-v: info, -vv: debug)")
    return parser


def configure_logging(verbosity: int, stream=None) -> logging.Handler:
    """Show the first-party loggers' records on ``stream`` (stderr) from a level set by ``-v``.

    Parameters
    ----------
    verbosity : int
        0: warnings and errors; 1 (``-v``): info; 2 or more (``-vv``): debug.
    stream : file, optional
        Where records go (default ``sys.stderr``).

    Returns
    -------
    logging.Handler
        The handler added to each logger of :data:`LOGGED_PACKAGES` (replacing one an
        earlier call added), so repeated calls in one process do not duplicate lines.

    Examples
    --------
    >>> import io, logging
    >>> out = io.StringIO()
    >>> _ = configure_logging(1, out)
    >>> logging.getLogger("compiler.passes").info("calibrate: 3 frames")
    >>> logging.getLogger("compiler.passes").debug("not shown at -v")
    >>> out.getvalue()
    'compiler.passes: calibrate: 3 frames\\n'
    >>> _ = configure_logging(0)
    """
    level = (logging.WARNING, logging.INFO)[verbosity] if verbosity < 2 else logging.DEBUG
    handler = logging.StreamHandler(sys.stderr if stream is None else stream)
    handler.setFormatter(logging.Formatter("%(name)s: %(message)s"))
    handler.set_name("radarsnn-cli")
    for name in LOGGED_PACKAGES:
        log = logging.getLogger(name)
        for old in [h for h in log.handlers if h.get_name() == "radarsnn-cli"]:
            log.removeHandler(old)
        log.addHandler(handler)
        log.setLevel(level)
    return handler


def _error_exit(err: BaseException, args: argparse.Namespace | None) -> int:
    message = " ".join(str(err).split())  # one line, whatever a library put in the message
    if isinstance(err, OSError) and not isinstance(err, RadarSNNError):
        message = f"{err.strerror or err}: {err.filename}" if err.filename else str(err)
    if args is not None and getattr(args, "json", False):
        print(json.dumps({"error": message, "type": type(err).__name__,
                          "node": getattr(err, "node", None)}, sort_keys=True))
    else:
        print(f"error: {message}", file=sys.stderr)
    return EXIT_USAGE if isinstance(err, UsageError) else EXIT_ERROR


def _silence_stdout() -> None:
    """Point stdout at the null device, so the interpreter's final flush cannot fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # not a file descriptor (a test's capture)
        pass


def _modules_for(argv: Sequence[str]) -> tuple[ModuleType, ...] | None:
    """The modules ``argv`` needs: its command's, none for a bare ``--version``, else all.

    Examples
    --------
    >>> [m.__name__ for m in _modules_for(["-v", "run", "DIR"])]
    ['radarsnn.cli.run']
    >>> _modules_for(["--version"]), _modules_for([])
    ((), None)
    """
    for arg in argv:  # the options before the command take no value
        if arg in COMMANDS:
            return (COMMANDS[arg](),)
        if not arg.startswith("-"):
            return None  # an unknown command: every module, for argparse's message
    return () if "--version" in argv and not {"-h", "--help"} & set(argv) else None


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Print a warning as one line ``warning: <message>`` (whitespace folded) on stderr.

    The :func:`warnings.showwarning` of every command (its signature); the category, file
    and line of Python's form are left out: the message names the node and the fix.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> show_warning(UserWarning("node 'f': drift 0.14,  over N=1024"), UserWarning,
    ...              "x.py", 3, file=out)
    >>> out.getvalue()
    "warning: node 'f': drift 0.14, over N=1024\\n"
    """
    print("warning: " + " ".join(str(message).split()), file=file or sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 1 runtime error, 2 usage error)."""
    argv_given, argv = argv, list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser(_modules_for(argv)).parse_args(argv)
    except UsageError as err:
        return _error_exit(err, argparse.Namespace(json="--json" in argv))
    configure_logging(args.verbose)
    if argv_given is None and getattr(args, "holds_freed_memory", False):
        from backends.reference.heap import hold_freed_memory

        hold_freed_memory()  # this process is the radarsnn command: its heap is its own
    try:
        with warnings.catch_warnings():  # restores showwarning when the command ends
            warnings.showwarning = show_warning
            return args.func(args)
    except BrokenPipeError:  # the reader stopped (`radarsnn schema | head`): it had its output
        _silence_stdout()
        return 0
    except (RadarSNNError, OSError, UsageError) as err:
        if args.debug:
            raise
        return _error_exit(err, args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
