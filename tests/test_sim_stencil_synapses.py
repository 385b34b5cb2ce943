"""The stencil delivery's per-neuron synapse counts (taps inside the map) from per-axis
tables equal the counts made tap by tap for every source neuron (any axes, edges, delays)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.stencil import StencilDelivery
from compiler.snn import Population, StencilProjection

NAMES = ("rx", "doppler", "range", "angle")


@settings(max_examples=200, deadline=None)
@given(data=st.data(), n_dims=st.integers(1, 4), seed=st.integers(0, 2 ** 16))
def test_synapse_counts_equal_the_tap_by_tap_counts(data, n_dims, seed):
    rng = np.random.default_rng(seed)
    names = NAMES[:n_dims]
    sizes = {a: data.draw(st.integers(1, 7)) for a in names}
    n_map = data.draw(st.integers(1, n_dims))
    axes = tuple(data.draw(st.permutations(names))[:n_map])
    radius = [data.draw(st.integers(0, 3)) for _ in axes]
    kernel = rng.integers(-2, 3, tuple(2 * r + 1 for r in radius)).astype(float)
    kernel *= rng.random(kernel.shape) < 0.7  # holes, as a CFAR's guard cells
    edge = tuple(data.draw(st.sampled_from(["wrap", "clip"])) for _ in axes)
    delays = (rng.integers(0, 3, kernel.shape) if data.draw(st.booleans()) else None)
    proj = StencilProjection(id="s", source="a", target="b", axes=axes, kernel=kernel,
                             edge=edge, delays=delays)
    src_order = data.draw(st.permutations(names))
    tgt_order = data.draw(st.permutations(names))
    src = Population(id="a", shape={a: sizes[a] for a in src_order}, source=True)
    tgt = Population(id="b", shape={a: sizes[a] for a in tgt_order})
    d = StencilDelivery.build(proj, src, tgt, integer=bool(data.draw(st.booleans())))
    for k in range(len(d.delays)):
        fast, slow = d._count_synapses(k), d._count_synapses_by_events(k)
        assert fast.dtype == slow.dtype and fast.shape == slow.shape
        np.testing.assert_array_equal(fast, slow)
        np.testing.assert_array_equal(d.synapses[k], slow)


def test_a_hand_worked_count():
    # 1-D, clip, taps at -1 and +1 over 4 cells: the end cells keep one tap each
    k = StencilProjection(id="s", source="a", target="b", axes=("r",),
                          kernel=np.array([1.0, 0.0, 2.0]), edge=("clip",))
    d = StencilDelivery.build(k, Population(id="a", shape={"r": 4}, source=True),
                              Population(id="b", shape={"r": 4}))
    assert d._count_synapses(0).tolist() == [1, 2, 2, 1]
    # 2-D, clip x wrap: the wrapped axis never loses a tap
    k2 = StencilProjection(id="s", source="a", target="b", axes=("r", "d"),
                           kernel=np.ones((3, 3)), edge=("clip", "wrap"))
    d2 = StencilDelivery.build(k2, Population(id="a", shape={"r": 3, "d": 2}, source=True),
                               Population(id="b", shape={"d": 2, "r": 3}))
    assert d2._count_synapses(0).tolist() == [6, 6, 9, 9, 6, 6]
