"""radarsnn's public face: compile a radar DSP chain into a spiking network and run it.

The project's own packages stay where the design puts them (``ir``, ``compiler``,
``backends``, ``radar``); this package gathers what a user needs first under one name.
It is also the application layer: the ``radarsnn`` command (:mod:`radarsnn.cli`), the
demo (:mod:`radarsnn.demo`), the sweeps (:mod:`radarsnn.sweep`) and the benchmark
(:mod:`radarsnn.bench`).  A name is imported from its home module on first use, so the
command line starts without loading numpy and the compiler.

Examples
--------
>>> import numpy as np
>>> import radarsnn
>>> g = radarsnn.Graph(name="sq")
>>> _ = g.add(radarsnn.Output(), g.add(radarsnn.Magnitude(kind="square"),
...                                    g.add(radarsnn.Input(shape={"range": 3}), id="a")))
>>> program = radarsnn.compile_graph(g, target=None)
>>> radarsnn.run_program(program, {"a": np.array([1.0, -2.0, 3.0])}).outputs[
...     g.output_ids()[0]].tolist()
[1.0, 4.0, 9.0]
>>> isinstance(radarsnn.__version__, str)
True
"""

from __future__ import annotations

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from ir import errors as _errors
from ir.errors import *  # noqa: F403  (every error class: RadarSNNError and its subclasses)

try:
    __version__ = version("radarsnn")
except PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0.0.0+unknown"

#: The home module of each public name outside :mod:`radarsnn._chain`, imported when the name
#: is first read; every name of ``radarsnn._chain.__all__`` (the IR ops, example chains, radar
#: presets and scenes) is read from there.
HOMES: dict[str, tuple[str, ...]] = {
    "backends": ("load", "load_program", "save", "save_program"),
    "backends.reference": ("run_program", "simulate"),
    "backends.reference.accuracy": ("check_accuracy",),
    "backends.reference.frames_pool": ("close_frame_workers",),
    "backends.reference.heap": ("hold_freed_memory",),
    "compiler.program": ("CompiledProgram",),
    "ir": ("Graph", "evaluate"),
    "radarsnn.compile": ("compile_graph",),
}
_HOME_OF = {name: module for module, names in HOMES.items() for name in names}
_CHAIN = "radarsnn._chain"


def __getattr__(name: str) -> Any:
    """Import a public name from its home module (PEP 562) and keep it here.

    ``__all__`` too is made on first use: it takes the chain module's names.
    """
    if name == "__all__":
        value = list(dict.fromkeys(["__version__", *_errors.__all__, *_HOME_OF,
                                    *import_module(_CHAIN).__all__]))
    elif name in _HOME_OF:
        value = getattr(import_module(_HOME_OF[name]), name)
    elif name.startswith("__") or name not in import_module(_CHAIN).__all__:
        raise AttributeError(f"module 'radarsnn' has no attribute {name!r}")
    else:
        value = getattr(import_module(_CHAIN), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__getattr__("__all__")))
