"""radarsnn's public face: compile a radar DSP chain into a spiking network and run it.

The project's own packages stay where the design puts them (``ir``, ``compiler``,
``backends``, ``radar``); this package gathers what a user needs first under one name.

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

from importlib.metadata import PackageNotFoundError, version

from backends import load, load_program, save, save_program
from backends.reference import run_program, simulate
from backends.reference.accuracy import check_accuracy
from compiler.program import CompiledProgram
from ir import Graph, evaluate
from ir import errors as _errors
from ir.errors import *  # noqa: F403  (every error class: RadarSNNError and its subclasses)
from radarsnn._chain import *  # noqa: F403  (every IR op, chains, radar presets, scenes)
from radarsnn._chain import __all__ as _chain_names
from radarsnn.compile import compile_graph

try:
    __version__ = version("radarsnn")
except PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = [
    "CompiledProgram", "Graph", "__version__",
    "check_accuracy", "compile_graph",
    "evaluate", "load", "load_program", "run_program", "save", "save_program",
    "simulate", *_errors.__all__, *_chain_names,
]
