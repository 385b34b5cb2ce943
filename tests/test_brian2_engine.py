"""A whole compiled program runs on Brian2 through ``run_program(engine=Brian2Engine())``.

The host nodes are evaluated as always; the spiking segment (a time-coded S-FT with
8-bit weights: exact current sums) is simulated by Brian2, and the program's every value
equals the reference step engine's, frame by frame and over a frames axis.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("brian2", reason="Brian2 is the optional extra 'brian2' "
                    "(pip install 'radarsnn[brian2]'); CI installs it")

from backends.brian2 import Brian2Engine  # noqa: E402
from backends.reference import run_program  # noqa: E402
from backends.reference.engine import REFERENCE, SegmentEngine  # noqa: E402
from compiler.compile import compile_graph  # noqa: E402
from ir import Graph  # noqa: E402
from ir.errors import SimulationError  # noqa: E402

G = Graph.from_dict({"name": "rng", "nodes": [
    {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 32}},
    {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
    {"id": "m", "op": "magnitude", "input": "f", "kind": "square"},
    {"id": "o", "op": "output", "input": "m"}]})
X = np.random.default_rng(4).normal(size=(3, 2, 32))


@pytest.fixture(scope="module")
def program():
    return compile_graph(G, "unbounded", calibration_inputs={"x": X[:2]},
                         motifs={"f": "time", "m": "host"}, time_steps=32, weight_bits=8)


def test_a_program_on_brian2_equals_the_step_engine(program):
    assert [s.kind for s in program.segments][:2] == ["spiking", "host"]
    ours = run_program(program, {"x": X[2]}, mode="step")
    theirs = run_program(program, {"x": X[2]}, engine=Brian2Engine())
    assert theirs.mode == "brian2-numpy" and ours.mode == "step"
    assert set(theirs.values) == set(ours.values)
    for node, value in ours.values.items():
        np.testing.assert_array_equal(theirs.values[node], value, err_msg=node)
    assert theirs.spike_counts == ours.spike_counts and ours.total_spikes > 0


def test_a_frames_axis_on_brian2_equals_the_step_engine(program):
    ours = run_program(program, {"x": X}, mode="step", workers=1)
    theirs = run_program(program, {"x": X}, engine=Brian2Engine(), workers=1)
    np.testing.assert_array_equal(theirs.outputs["o"], ours.outputs["o"])


def test_the_engine_is_checked():
    assert isinstance(REFERENCE, SegmentEngine) and isinstance(Brian2Engine(), SegmentEngine)
    with pytest.raises(SimulationError, match="engine=.*has no name and simulate"):
        run_program(compile_graph(G, None, calibration_inputs={"x": X[:2]}), {"x": X[0]},
                    engine=object())
    with pytest.raises(SimulationError, match="not one of"):
        Brian2Engine("fortran")
