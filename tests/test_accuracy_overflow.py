"""The accuracy contract refuses a stage whose states leave the chip's range.

The reference simulator computes wider than a chip's ``state_bits``; where a stage's
membrane or current leaves ``±(2^(b−1) − 1)`` the chip wraps ``u`` and saturates ``v``, so
the simulated figures are not what the chip computes: the contract must say so, naming
the stage, whatever its other figures.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from compiler.accuracy.check import check_program
from compiler.accuracy.simulator import SimulatedFrames
from compiler.compile import compile_graph
from ir import Graph, evaluate

G = Graph.from_dict({"name": "r", "nodes": [
    {"id": "x", "op": "input", "shape": {"sample": 16}},
    {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
    {"id": "o", "op": "output", "input": "f"}]})
X = np.random.default_rng(0).normal(size=(2, 16))


class Golden:
    """Returns the golden values, and ``overflow`` neuron-steps on population ``pop``."""

    name = "golden"

    def __init__(self, overflow: dict[str, int]) -> None:
        self.overflow = overflow

    def run(self, program, inputs):
        sim = SimpleNamespace(state_overflow=self.overflow)
        return SimulatedFrames(values=evaluate(program.graph, inputs), simulations=(sim,))


@pytest.fixture(scope="module")
def program():
    return compile_graph(G, "loihi2", calibration_inputs={"x": X})


def test_exact_values_hold_without_overflow(program):
    assert check_program(program, {"x": X}, Golden({})).holds


def test_a_stage_whose_states_leave_the_range_fails_and_is_named(program):
    (seg,) = [s for s in program.segments if s.kind == "spiking"]
    pop = next(p.id for p in seg.network.populations if p.origin.get("node") == "f")
    contract = check_program(program, {"x": X}, Golden({pop: 7}))
    assert not contract.holds
    ((stage, failures),) = contract.failing()
    assert stage.node == "f" and stage.overflow == 7
    assert failures[0].startswith("7 neuron-steps beyond the chip's state range")
    assert "7 states out of range" in stage.describe()
    assert contract.to_dict()["stages"][0]["overflow"] == 7


def test_overflow_of_another_network_is_not_charged_to_this_stage(program):
    assert check_program(program, {"x": X}, Golden({"elsewhere/pop": 5})).holds
