"""Split: per-block demand against a brute-force synapse enumeration; budgets; BudgetError."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from compiler.hardware import Blocks, HardwareProfile, block_demand, load_profile
from compiler.hardware.demand import stencil_degree_map, stored_synapses
from compiler.hardware.reference_networks import dft_network, imaging_network, os_cfar_network
from compiler.hardware.repetition import instance_neurons, stages
from compiler.passes.base import CompileContext
from compiler.passes.place import Place, place
from compiler.passes.split import REPETITION_MODES, Split, split
from compiler.program import CompiledProgram, Segment
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import BudgetError

CODE = LatencyCode(t_max=8, x_min=0.0, x_max=1.0)


# ----------------------------------------------------------------------------- brute force
def synapse_list(net: SpikingNetwork) -> list[tuple[str, str, int, int, tuple]]:
    """Every synapse instance as (source pop, target pop, source flat, target flat, weight key)."""
    pops = net.population
    out = []
    for p in net.projections:
        src, tgt = pops[p.source], pops[p.target]
        for t in range(tgt.size):
            tc = dict(zip(tgt.axes, np.unravel_index(t, tgt.dims), strict=True))
            if isinstance(p, MatrixProjection):
                w = p.weights if p.weights is not None else p.by_delay()[0].toarray()
                col = np.ravel_multi_index([tc[a] for a in p.produce],
                                           [tgt.shape[a] for a in p.produce])
                for row in np.flatnonzero(w[:, col]):
                    cc = dict(zip(p.contract, np.unravel_index(
                        row, [src.shape[a] for a in p.contract]), strict=True))
                    sc = [cc[a] if a in cc else tc[a] for a in src.axes]
                    out.append((p.source, p.target, int(np.ravel_multi_index(sc, src.dims)), t,
                                (p.id, int(col))))
            else:
                for tap in np.argwhere(p.kernel != 0):
                    sc, ok = dict(tc), True
                    for i, a in enumerate(p.axes):
                        c = tc[a] + tap[i] - p.radius[i]
                        if p.edge[i] == "wrap":
                            c %= tgt.shape[a]
                        ok &= 0 <= c < tgt.shape[a]
                        sc[a] = c
                    if ok:
                        flat = int(np.ravel_multi_index([sc[a] for a in src.axes], src.dims))
                        out.append((p.source, p.target, flat, t, (p.id, "kernel")))
    return out


def brute_demand(net, pop_id, edges, bits, shared, neurons=None):
    """Per-block amounts by enumeration; block b holds ``neurons[edges[b]:edges[b+1]]``."""
    syn = synapse_list(net)
    nb = len(edges) - 1
    neurons = np.arange(edges[-1]) if neurons is None else np.asarray(neurons)
    res = np.zeros((nb, 4), np.int64)
    kernel_taps = {p.id: p.n_taps for p in net.projections if isinstance(p, StencilProjection)}
    for b in range(nb):
        members = set(neurons[edges[b]:edges[b + 1]].tolist())
        lo, hi = 0, len(members)
        res[b, 0] = len(members)
        into = [s for s in syn if s[1] == pop_id and s[3] in members]
        res[b, 1] = len({(s[0], s[2]) for s in into})
        res[b, 2] = len({(s[1], s[2]) for s in syn if s[0] == pop_id and s[2] in members})
        if shared:
            keys = {s[4] for s in into}
            ent = 0
            for key in keys:
                ent += kernel_taps[key[0]] if key[1] == "kernel" else sum(
                    1 for s in syn if s[4] == key and s[3] == into[0][3] or False)
            # matrix columns: the number of synapses of that column in ONE repetition
            ent = 0
            for key in keys:
                if key[1] == "kernel":
                    ent += kernel_taps[key[0]]
                else:
                    p = net.projection[key[0]]
                    w = p.weights if p.weights is not None else p.by_delay()[0].toarray()
                    ent += int(np.count_nonzero(w[:, key[1]]))
            # a stencil kernel is charged even when every tap of the block is clipped
            for p in net.incoming(pop_id):
                if isinstance(p, StencilProjection) and (p.id, "kernel") not in keys and hi > lo:
                    ent += p.n_taps
        else:
            ent = len(into)
        res[b, 3] = ent * bits
    return res


# ----------------------------------------------------------------------------- random networks
@st.composite
def networks(draw):
    r = draw(st.integers(1, 3))
    n_in, n_out = draw(st.integers(1, 4)), draw(st.integers(1, 4))
    rep_last = draw(st.booleans())
    src = Population(id="x", shape={"r": r, "i": n_in}, source=True)
    p1_shape = {"o": n_out, "r": r} if rep_last else {"r": r, "o": n_out}
    p1 = Population(id="a", shape=p1_shape, origin={"node": "n1", "motif": "m1"})
    p2 = Population(id="b", shape=dict(p1_shape), origin={"node": "n2", "motif": "m2"})
    mask = draw(st.lists(st.booleans(), min_size=n_in * n_out, max_size=n_in * n_out))
    w = np.where(np.array(mask).reshape(n_in, n_out), 1.0, 0.0)
    projs = [MatrixProjection(id="w1", source="x", target="a", contract=("i",),
                              produce=("o",), weights=w)]
    if draw(st.booleans()):
        rows, cols = np.nonzero(np.ones((n_in, n_out)))
        keep = np.array(draw(st.lists(st.booleans(), min_size=rows.size, max_size=rows.size)))
        projs.append(MatrixProjection(id="w2", source="x", target="a", contract=("i",),
                                      produce=("o",), rows=rows[keep], cols=cols[keep],
                                      values=np.ones(int(keep.sum())), n_in_out=(n_in, n_out)))
    axes = draw(st.sampled_from([("o",), ("r", "o"), ("o", "r")]))
    kshape = tuple(draw(st.sampled_from([1, 3, 5])) for _ in axes)
    kmask = draw(st.lists(st.booleans(), min_size=int(np.prod(kshape)),
                          max_size=int(np.prod(kshape))))
    kernel = np.where(np.array(kmask).reshape(kshape), -1.0, 0.0)
    edges = tuple(draw(st.sampled_from(["clip", "wrap"])) if n >= 2 * (k // 2) + 1
                  else "clip" for n, k in zip([p1_shape[a] for a in axes], kshape, strict=True))
    projs.append(StencilProjection(id="s", source="a", target="b", axes=axes, kernel=kernel,
                                   edge=edges))
    return SpikingNetwork(name="rand", n_steps=4, populations=[src, p1, p2], projections=projs,
                          encoders=[Encoder(port="x", population="x", code=CODE)]).validate()


def profiles():
    lim = st.one_of(st.none(), st.integers(1, 40))
    return st.builds(HardwareProfile, name=st.just("rand"), cores_per_chip=st.integers(1, 6),
                     chips=st.integers(1, 3), neurons_per_core=st.integers(1, 12),
                     input_axons_per_core=lim, output_axons_per_core=lim,
                     synapse_memory_bits_per_core=st.one_of(st.none(), st.integers(1, 400)),
                     bits_per_synapse=st.integers(1, 16),
                     shared_weights_per_core=st.booleans())


@given(networks(), st.data())
def test_block_demand_matches_brute_force(net, data):
    shared = data.draw(st.booleans())
    for pop in ("a", "b"):
        size = net.population[pop].size
        n = data.draw(st.integers(1, size))
        blocks = Blocks.uniform(pop, size, n)
        got = block_demand(net, pop, blocks, bits_per_synapse=3, shared_weights=shared)
        want = brute_demand(net, pop, blocks.edges, 3, shared)
        np.testing.assert_array_equal(got.amounts, want)


def allocate(net, profile, mode):
    """The Split and Place passes (with auto's escalation) on one network."""
    prog = CompiledProgram(graph=None, segments=[
        Segment(kind="spiking", inputs=[], outputs=[], network=net)])
    ctx = CompileContext(target=profile)
    prog = Place(repetitions=mode).apply(ctx, Split(repetitions=mode).apply(ctx, prog))
    return prog.records["split"][0], prog.records["placement"]


@given(networks(), profiles(), st.sampled_from(REPETITION_MODES))
@settings(max_examples=60)
def test_split_and_place_respect_every_budget(net, profile, mode):
    try:
        rec, placement = allocate(net, profile, mode)
    except BudgetError as err:
        assert err.node is not None and str(profile.name) in str(err)
        return
    limits = profile.limits()
    assert np.all(placement.usage <= limits)                      # no core exceeds a budget
    assert placement.n_cores <= profile.n_cores
    if mode == "spatial":
        assert rec.multiplexed == {}
    reps = {st.key: st for st in stages(net)}
    for pid, dem in rec.demand.items():  # every neuron (of one instance if multiplexed) once
        key = rec.stage_of[pid]
        e, pop = dem.blocks.edges, net.population[pid]
        if key in rec.multiplexed:
            assert rec.multiplexed[key] == reps[key].repetitions > 1
            want = instance_neurons(pop, reps[key].axes)
            np.testing.assert_array_equal(dem.blocks.neurons, want)
            assert e[-1] == pop.size // reps[key].repetitions
        else:
            assert dem.blocks.neurons is None and e[-1] == pop.size
        assert e[0] == 0 and np.all(np.diff(e) > 0)
    assert sorted(placement.items) == sorted({*placement.items})
    if not profile.shared_weights_per_core and not rec.multiplexed:  # every synapse once
        total = sum(int(d.entries.sum()) for d in rec.demand.values())
        assert total == stored_synapses(net, False) == len(synapse_list(net))
    rec2, again = allocate(net, profile, mode)                     # deterministic
    np.testing.assert_array_equal(again.core, placement.core)
    assert rec2.multiplexed == rec.multiplexed
    assert [d.blocks.edges.tolist() for d in rec2.demand.values()] == \
        [d.blocks.edges.tolist() for d in rec.demand.values()]


@given(networks(), st.data())
def test_block_demand_of_one_instance_matches_brute_force(net, data):
    (st_a,) = [s for s in stages(net) if s.key == "n1"]
    pop = net.population["a"]
    neurons = instance_neurons(pop, st_a.axes)
    assert len(neurons) * st_a.repetitions == pop.size
    n = data.draw(st.integers(1, len(neurons)))
    shared = data.draw(st.booleans())
    blocks = Blocks.uniform("a", len(neurons), n, neurons=neurons)
    got = block_demand(net, "a", blocks, bits_per_synapse=3, shared_weights=shared)
    want = brute_demand(net, "a", blocks.edges, 3, shared, neurons)
    np.testing.assert_array_equal(got.amounts, want)


def test_one_neuron_over_budget_names_node_motif_budget_amount_limit():
    net = os_cfar_network(16, 32)
    prof = HardwareProfile(name="tiny", cores_per_chip=64, chips=64, neurons_per_core=64,
                           input_axons_per_core=100, synapse_memory_bits_per_core=10**9)
    with pytest.raises(BudgetError, match=r"node 'det' \(motif os_cfar.*one neuron per core "
                       r"needs 177 input axons.*tiny allows 100.*reduce the fan-in") as e:
        split(net, prof)
    assert e.value.node == "det"


def test_total_over_chip_suggests_chips():
    with pytest.raises(BudgetError, match=r"needs 327,155,712 neurons.*39,936 cores \(312 "
                       r"chips.*node 'rng' \(motif dft.*on the host"):
        split(imaging_network(), load_profile("loihi2"))


def test_hand_worked_blocks_of_a_1d_stencil():
    # 6 neurons, kernel [1, 0, 1] clipped: in-degrees 1,2,2,2,2,1
    net = SpikingNetwork(name="h", n_steps=2, populations=[
        Population(id="x", shape={"r": 6}, source=True), Population(id="y", shape={"r": 6})],
        projections=[StencilProjection(id="k", source="x", target="y", axes=("r",),
                                       kernel=np.array([1.0, 0.0, 1.0]), edge=("clip",))])
    d = block_demand(net, "y", Blocks.uniform("y", 6, 2), bits_per_synapse=8,
                     shared_weights=False)
    # block 0 = y0..y2 reads x1, x0, x2, x1, x3 -> {0,1,2,3}; block 1 = y3..y5 -> {2,3,4,5}
    assert d.amounts.tolist() == [[3, 4, 0, 40], [3, 4, 0, 40]]
    d = block_demand(net, "y", Blocks.uniform("y", 6, 2), bits_per_synapse=8,
                     shared_weights=True)
    assert d.amounts[:, 3].tolist() == [16, 16]
    assert stencil_degree_map(net.projections[0], net.population["y"],
                              incoming=True).tolist() == [1, 2, 2, 2, 2, 1]


def test_os_cfar_stand_in_on_loihi_is_exact():
    net = os_cfar_network()
    rec = split(net, load_profile("loihi"))
    pl = place([net], [rec], load_profile("loihi"))
    dem = rec.demand["det"]
    # unshared memory: every synapse inside the map; range clipped loses edge taps
    assert int(dem.entries.sum()) == stored_synapses(net, False) == 2_851_584
    # 2 851 584 x 24 bit / 1 Mbit = 65.3 -> at least 66 cores; 67 is the fewest uniform fit
    assert dem.blocks.n_blocks == pl.n_cores == 67
    assert np.all(pl.usage <= load_profile("loihi").limits())


def test_dense_dft_on_loihi_does_not_fit_by_memory():
    # 4 x 64 repetitions of a dense 512 x 1024 matrix = 134 217 728 synapses x 24 bit = 3 072 Mbit
    with pytest.raises(BudgetError, match=r"needs 3,221,225,472 bits of synaptic memory.*at "
                       r"least 3,072 cores.*node 'rng' \(motif dft.*sparser matrix"):
        split(dft_network(), load_profile("loihi"))
