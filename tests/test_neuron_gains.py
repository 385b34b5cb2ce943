"""``Decoder.neuron_gains``: the gains broadcast along their axis of the population, flat in
memory order (the repeated-run construction equals the plain broadcast, every axis position)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from compiler.snn.coding import Decoder


@settings(max_examples=60, deadline=None)
@given(sizes=st.lists(st.integers(1, 6), min_size=1, max_size=4), data=st.data(),
       seed=st.integers(0, 2 ** 16))
def test_neuron_gains_are_the_broadcast_gains(sizes, data, seed):
    shape = {f"a{i}": n for i, n in enumerate(sizes)}
    k = data.draw(st.integers(0, len(sizes) - 1))
    gains = tuple(np.random.default_rng(seed).uniform(0.1, 4.0, sizes[k]))
    dec = Decoder(port="y", population="p", kind="membrane", gain_axis=f"a{k}", gains=gains)
    view = [1] * len(sizes)
    view[k] = sizes[k]
    want = np.broadcast_to(np.asarray(gains).reshape(view), tuple(sizes)).ravel()
    got = dec.neuron_gains(shape)
    assert got.dtype == np.float64 and got.shape == want.shape
    np.testing.assert_array_equal(got, want)


def test_hand_worked_gains():
    dec = Decoder(port="y", population="p", kind="membrane", gain_axis="b", gains=(2.0, 4.0))
    assert dec.neuron_gains({"a": 2, "b": 2, "c": 1}).tolist() == [2.0, 4.0, 2.0, 4.0]
    assert dec.neuron_gains({"b": 2, "c": 3}).tolist() == [2.0] * 3 + [4.0] * 3
