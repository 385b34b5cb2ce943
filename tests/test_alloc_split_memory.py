"""Split memory: one block of a whole population is measured without per-neuron arrays.

On ``unbounded`` every population is one block; building the per-neuron prefix
sums for it (some 200 bytes per neuron at their peak) made the 327 M-neuron
imaging network need 17.6 GB.  These tests pin that the one-block totals equal
what the prefix sums give, and that the split's peak memory stays proportional
to the network's size with a small constant (no timed tests).
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from compiler.hardware import Blocks, load_profile
from compiler.hardware import demand as demand_module
from compiler.hardware.demand import demand_model
from compiler.hardware.reference_networks import imaging_network, os_cfar_network
from compiler.hardware.synapses import nonzero_pattern
from compiler.passes.split import split

#: Bytes the unbounded split may hold at once per (neuron of the largest population + stored
#: matrix weight); the per-neuron prefix sums alone need more than 32 per neuron.
BYTES_PER_ITEM = 32


@pytest.mark.parametrize("shared", [True, False])
@pytest.mark.parametrize("network", [lambda: imaging_network(2, 16, 16, n_steps=10),
                                     lambda: os_cfar_network(16, 32)],
                         ids=["imaging", "os_cfar"])
@pytest.mark.parametrize("instance", [False, True])
def test_one_block_totals_equal_the_prefix_sums(network, shared, instance):
    net = network()
    for pop in net.populations:
        if pop.source:
            continue
        neurons = np.arange(1, pop.size, 3, dtype=np.int64) if instance else None
        n = pop.size if neurons is None else len(neurons)
        model = demand_model(net, pop.id, neurons, shared_weights=shared)
        whole = Blocks(pop.id, np.array([0, n]), neurons)
        # the same neurons as the first of two blocks (the second empty): the prefix sums
        cut = Blocks(pop.id, np.array([0, n, n]), neurons)
        got = model.amounts(whole, bits_per_synapse=3, fan_in=True)
        want = model.amounts(cut, bits_per_synapse=3, fan_in=True)[:1]
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(model.entries(whole), model.entries(cut)[:1])
        dem = model.demand(whole, bits_per_synapse=3, reach=True)
        np.testing.assert_array_equal(dem.amounts, want)


@pytest.mark.parametrize("shape", [(16, 16, 32), (16, 32, 64)])
def test_unbounded_split_memory_is_proportional_to_the_network(monkeypatch, shape):
    # small chunks, so that a network of 10^5 neurons shows how memory scales with size
    monkeypatch.setattr(demand_module, "_CHUNK", 1 << 10)
    net = imaging_network(*shape, n_steps=10)
    largest = max(p.size for p in net.populations)
    weights = sum(nonzero_pattern(p).nnz for p in net.projections if p.kind == "matrix")
    tracemalloc.start()
    try:
        rec = split(net, load_profile("unbounded"))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert all(d.blocks.n_blocks == 1 for d in rec.demand.values())
    # shared weights on unbounded: each matrix stored once, the OS-CFAR kernel once
    assert rec.demand["rng"].entries.tolist() == [nonzero_pattern(net.projection["rng_w"]).nnz]
    assert rec.demand["det"].entries.tolist() == [net.projection["det_window"].n_taps]
    assert peak < BYTES_PER_ITEM * (largest + weights), (peak, largest, weights)
