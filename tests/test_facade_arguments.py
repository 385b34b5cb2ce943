"""The public facade refuses arguments of the wrong type with the project's typed errors,
naming the function, the argument and what it takes (never a TypeError or AttributeError)."""

from __future__ import annotations

import numpy as np
import pytest

import radarsnn
from radarsnn import ArtifactError, CompileError, IRError, SimulationError

GRAPH = radarsnn.Graph(name="sq")
_ = GRAPH.add(radarsnn.Output(), GRAPH.add(radarsnn.Magnitude(kind="square"), GRAPH.add(
    radarsnn.Input(shape={"range": 3}), id="a")))
PROGRAM = radarsnn.compile_graph(GRAPH, target=None)
X = {"a": np.array([1.0, -2.0, 3.0])}


@pytest.mark.parametrize("call, error, match", [
    (lambda: radarsnn.load(3), ArtifactError, r"load\(directory=3\): .* path"),
    (lambda: radarsnn.load(None), ArtifactError, r"load\(directory=None\)"),
    (lambda: radarsnn.load(b"x"), ArtifactError, r"load\(directory=b'x'\)"),
    (lambda: radarsnn.load_program(3.5), ArtifactError, r"load_program\(directory=3.5\)"),
    (lambda: radarsnn.save_program(GRAPH, "x"), ArtifactError,
     r"save_program\(program=.*takes a CompiledProgram, not Graph"),
    (lambda: radarsnn.save_program(PROGRAM, None), ArtifactError,
     r"save_program\(directory=None\)"),
    (lambda: radarsnn.save(PROGRAM, 7), ArtifactError, r"save\(directory=7\)"),
    (lambda: radarsnn.save(None, "x"), ArtifactError, r"cannot save a NoneType"),
    (lambda: radarsnn.run_program(None, X), SimulationError,
     r"run_program\(program=None\): takes a CompiledProgram"),
    (lambda: radarsnn.run_program(GRAPH, X), SimulationError, r"not Graph"),
    (lambda: radarsnn.run_program(PROGRAM, X, progress=5), SimulationError,
     r"progress=5 is not callable"),
    (lambda: radarsnn.evaluate(None, X), IRError, r"evaluate\(graph=None\): takes an ir.Graph"),
    (lambda: radarsnn.evaluate(GRAPH, None), IRError, r"inputs must be a mapping"),
    (lambda: radarsnn.evaluate(GRAPH, [1.0]), IRError, r"inputs must be a mapping"),
    (lambda: radarsnn.check_accuracy(None, X), SimulationError,
     r"check_accuracy\(program=None\)"),
    (lambda: radarsnn.compile_graph(GRAPH, progress=5), CompileError,
     r"progress=5 is not callable"),
])
def test_wrong_argument_types_are_typed_errors(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_a_callable_progress_still_runs():
    seen = []
    out = radarsnn.run_program(PROGRAM, {"a": np.ones((2, 3))},
                               progress=lambda done, total: seen.append((done, total)))
    assert out.outputs[GRAPH.output_ids()[0]].shape == (2, 3) and seen[-1] == (2, 2)


def test_check_accuracy_needs_a_mapping_of_inputs():
    with pytest.raises(SimulationError, match="check_accuracy: inputs must be a mapping"):
        radarsnn.check_accuracy(PROGRAM, None)
