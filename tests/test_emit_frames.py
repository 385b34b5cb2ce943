"""A generated program package takes the framed inputs ``radarsnn run`` takes (every input
``(F, *declared)``): the frames run one after the other, outputs and spike counts equal to
``run_program``'s, bit for bit."""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest

from backends.emit import emit_numpy
from backends.reference import run_program
from compiler.compile import compile_graph
from ir import Graph

GRAPH = Graph.from_dict({"name": "framed", "nodes": [
    {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 16}},
    {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
    {"id": "m", "op": "magnitude", "input": "f"},
    {"id": "o", "op": "output", "input": "m"}]})
CAL = np.random.default_rng(0).standard_normal((3, 2, 16))


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    program = compile_graph(GRAPH, "loihi2", calibration_inputs={"x": CAL}, time_steps=32,
                            motifs={"m": "host"})
    folder = tmp_path_factory.mktemp("pkg")
    emit_numpy(program, folder, name="framed_pkg")
    sys.path.insert(0, str(folder))
    try:
        yield program, importlib.import_module("framed_pkg")
    finally:
        sys.path.remove(str(folder))
        sys.modules.pop("framed_pkg", None)


def test_framed_inputs_run_as_run_program_runs_them(package):
    program, pkg = package
    x = 0.5 * CAL
    ref = run_program(program, {"x": x}, mode="step")
    out, counts = pkg.run({"x": x}, with_counts=True)
    assert out["o"].shape == (3, 2, 8)
    np.testing.assert_array_equal(out["o"], ref.outputs["o"])
    assert counts == [ref.simulations[0].spike_counts]
    one = pkg.run({"x": x[1]})["o"]  # a single frame is unchanged
    np.testing.assert_array_equal(one, out["o"][1])


def test_a_wrong_frames_axis_is_an_input_error(package):
    _, pkg = package
    from framed_pkg._kernels import InputError

    with pytest.raises(InputError, match=r"expected \(2, 16\)|shape"):
        pkg.run({"x": np.zeros((3, 2, 15))})
    with pytest.raises(InputError, match="frames axis"):
        pkg.run({"x": np.zeros((0, 2, 16))})
