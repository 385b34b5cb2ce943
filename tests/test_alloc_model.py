"""The fast allocation model: per-neuron prefix sums, the fan-in sweep, lazy fan-in, caches."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from test_alloc_split import CODE, brute_demand, networks, synapse_list

from compiler.hardware import Blocks, HardwareProfile, block_demand
from compiler.hardware.demand import demand_model
from compiler.hardware.intsets import unique_inverse, unique_keys
from compiler.hardware.reach import reach_sweep
from compiler.passes.split import split, split_program
from compiler.snn import Encoder, MatrixProjection, Population, SpikingNetwork


def _net() -> SpikingNetwork:
    """y = W x over axis o, repeated over c; column synapse counts nnz(W[:, p]) = [2, 1, 0]."""
    w = np.array([[1.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    return SpikingNetwork(name="m", n_steps=2, populations=[
        Population(id="x", shape={"c": 2, "i": 2}, source=True),
        Population(id="y", shape={"c": 2, "o": 3})],
        projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
                                      produce=("o",), weights=w)],
        encoders=[Encoder(port="x", population="x", code=CODE)]).validate()


def test_entries_by_hand():
    # positions 0..5 have columns p = 0 1 2 0 1 2; blocks [0, 4) and [4, 6)
    net, blocks = _net(), Blocks("y", np.array([0, 4, 6]))
    unshared = block_demand(net, "y", blocks, bits_per_synapse=1, shared_weights=False)
    shared = block_demand(net, "y", blocks, bits_per_synapse=1, shared_weights=True)
    assert unshared.entries.tolist() == [2 + 1 + 0 + 2, 1 + 0]
    assert shared.entries.tolist() == [2 + 1 + 0, 1 + 0]   # columns {0, 1, 2} and {1, 2}
    # fan-in: block 0 reaches x[c=0, i=0..1] and x[c=1, i=0..1]; block 1 only x[c=1, i=0]
    assert shared.amounts[:, 1].tolist() == [4, 1]


@given(networks(), st.data())
def test_reached_pairs_match_brute_force(net, data):
    syn = synapse_list(net)
    for pop in ("a", "b"):
        size = net.population[pop].size
        blocks = Blocks.uniform(pop, size, data.draw(st.integers(1, size)))
        fan_in, reach = reach_sweep(net, pop, blocks)
        blk = blocks.block_of(np.arange(size))
        want: dict[str, set] = {}
        for s, t, j, i, _ in syn:
            if t == pop:
                want.setdefault(s, set()).add((int(blk[i]), j))
        got = {s: list(zip(b.tolist(), c.tolist(), strict=True)) for s, (b, c) in reach.items()}
        assert {s: set(v) for s, v in got.items() if v} == want
        assert all(len(v) == len(set(v)) for v in got.values())  # each pair once
        assert fan_in.sum() == sum(len(v) for v in want.values())


@given(networks(), st.data())
def test_model_of_an_instance_matches_brute_force(net, data):
    pop = net.population["a"]
    neurons = np.array(sorted(data.draw(st.sets(st.integers(0, pop.size - 1), min_size=1))))
    shared = data.draw(st.booleans())
    blocks = Blocks.uniform("a", len(neurons), data.draw(st.integers(1, len(neurons))),
                            neurons=neurons)
    model = demand_model(net, "a", neurons, shared_weights=shared)
    got = model.amounts(blocks, bits_per_synapse=2, fan_in=True)
    np.testing.assert_array_equal(got, brute_demand(net, "a", blocks.edges, 2, shared, neurons))


def test_fan_in_is_counted_on_first_use_and_remembered():
    net = _net()
    profile = HardwareProfile(name="p", cores_per_chip=8, chips=1, neurons_per_core=4,
                              input_axons_per_core=None, output_axons_per_core=None,
                              synapse_memory_bits_per_core=None, bits_per_synapse=8,
                              shared_weights_per_core=True)
    (dem,) = split(net, profile).demand.values()
    assert not dem.counted and dem.amounts_counted[:, 1].tolist() == [0, 0]
    # two blocks of 3 (one per c), each reaching both x[c, i] of its c (flat 2c + i)
    assert dem.amounts[:, 1].tolist() == [2, 2] and dem.counted
    blk, src = dem.reach["x"]
    assert sorted(zip(blk.tolist(), src.tolist(), strict=True)) == [(0, 0), (0, 1), (1, 2),
                                                                   (1, 3)]
    (again,) = split_program([net], profile)[0].demand.values()
    assert again is dem   # the split of an unchanged network is remembered


def test_model_is_rebuilt_when_the_network_changes():
    net = _net()
    first = demand_model(net, "y", shared_weights=True)
    assert demand_model(net, "y", shared_weights=True) is first
    assert demand_model(net, "y", shared_weights=False) is not first
    net.projections = [MatrixProjection(id="w", source="x", target="y", contract=("i",),
                                        produce=("o",), weights=np.ones((2, 3)))]
    rebuilt = demand_model(net, "y", shared_weights=True)
    assert rebuilt is not first
    assert rebuilt.entries(Blocks("y", np.array([0, 6]))).tolist() == [6]


@given(st.lists(st.integers(-50, 50), max_size=40))
def test_sorted_sets_equal_numpy_unique(values):
    x = np.array(values, dtype=np.int64)
    np.testing.assert_array_equal(unique_keys(x), np.unique(x))
    keys, inverse = unique_inverse(x)
    want_keys, want_inverse = np.unique(x, return_inverse=True)
    np.testing.assert_array_equal(keys, want_keys)
    np.testing.assert_array_equal(inverse, want_inverse.ravel())
