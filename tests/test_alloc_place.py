"""Placement: first-fit decreasing with locality, hand-worked traffic, replaceable placer."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from compiler.hardware import HardwareProfile
from compiler.passes.place import greedy_placer, place
from compiler.passes.split import split
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir.errors import BudgetError

PROFILE = HardwareProfile(name="two-by-two", cores_per_chip=2, chips=2, neurons_per_core=2)


def chain() -> SpikingNetwork:
    once = NeuronParams(reset="fire_once")
    return SpikingNetwork(name="c", n_steps=8, populations=[
        Population(id="x", shape={"i": 4}, source=True),
        Population(id="a", shape={"o": 4}, params=once, origin={"node": "A", "motif": "id"}),
        Population(id="b", shape={"o": 4}, params=once, origin={"node": "B", "motif": "all"})],
        projections=[
            MatrixProjection(id="xa", source="x", target="a", contract=("i",), produce=("o",),
                             weights=np.eye(4)),
            MatrixProjection(id="ab", source="a", target="b", contract=("o",), produce=("o",),
                             weights=np.ones((4, 4)))],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))]).validate()


def test_hand_worked_placement_and_traffic():
    net = chain()
    pl = place([net], None, PROFILE)
    # each block fills a core (2 neurons); Cuthill-McKee order a0 b0 b1 a1 pairs each a-block
    # with a b-block on one chip
    assert pl.items == [(0, "a", 0), (0, "a", 1), (0, "b", 0), (0, "b", 1)]
    assert pl.core.tolist() == [0, 3, 1, 2] and pl.chip.tolist() == [0, 1, 0, 1]
    assert pl.cores_of(0, "b") == [1, 2] and pl.n_chips == 2
    # x -> a: each a-core receives its 2 inputs (4 messages); a -> b: each b-core receives all
    # 4 a-neurons from other cores (8 messages), 2 of them from the other chip (4 in all);
    # one spike per neuron (fire-once)
    assert pl.traffic == {"host_input": 4.0, "inter_core": 8.0, "inter_chip": 4.0,
                          "buffered": 0.0, "not_counted": [], "basis": "bound"}
    # a -> b fan-out: each a neuron drives one target population: 2 lines per a-block
    assert pl.usage[:, 2].tolist() == [2, 0, 0, 2]
    assert pl.usage[:, 1].tolist() == [2, 4, 4, 2]


def test_measured_traffic_uses_spike_counts():
    net = chain()
    sim = SimpleNamespace(spike_counts={"x": 8, "a": 4, "b": 0}, n_frames=2)  # a: 0.5 / neuron
    pl = place([net], None, PROFILE, sim_results=[sim])
    assert pl.traffic["inter_core"] == 4.0 and pl.traffic["host_input"] == 4.0
    assert pl.traffic["basis"] == "measured"


def test_locality_puts_connected_blocks_together():
    # blocks 0 and 3 exchange synapses; capacity two blocks per core
    core = greedy_placer(np.array([[1.0], [1.0], [1.0], [1.0]]), np.array([2.0]),
                         np.array([[0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0]]),
                         None)
    assert core[0] == core[3] and core[1] != core[0]


def test_placer_is_replaceable_and_out_of_cores_raises():
    net = chain()

    def one_per_core(demand, limits, affinity, n_cores):
        return np.arange(len(demand))

    kept = place([net], None, PROFILE, placer=one_per_core, chip_assignment="placer")
    assert kept.core.tolist() == [0, 1, 2, 3] and kept.traffic["inter_chip"] == 8.0
    # the chip assignment regroups the placer's cores (a0 a1 | b0 b1 -> a0 b0 | a1 b1): every
    # b-core then gets 2 of its 4 a-spikes from the other chip instead of all 4
    regrouped = place([net], None, PROFILE, placer=one_per_core)
    assert regrouped.core.tolist() == [0, 2, 1, 3] and regrouped.traffic["inter_chip"] == 4.0
    small = PROFILE.model_copy(update={"chips": 1})
    with pytest.raises(BudgetError, match=r"node '[AB]' \(motif .*4 blocks.*2 cores of "
                       r"two-by-two.*2 blocks were left over.*larger 'chips'"):
        place([net], [split(net, PROFILE)], small)


def test_two_networks_share_the_cores():
    net = chain()
    pl = place([net, net], None, PROFILE.model_copy(update={"chips": 4}))
    assert pl.n_cores == 8 and {i for i, _, _ in pl.items} == {0, 1}
