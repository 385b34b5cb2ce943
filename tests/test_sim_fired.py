"""The closed form's first-spike records: events on demand, and the silent span's dense
arrival features equal to delivering the events (bit for bit)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.closed import _synaptic_events
from backends.reference.delivery import DELIVERY_BUILDERS
from backends.reference.fired import Fired
from backends.reference.spans import Arrivals
from compiler.snn import MatrixProjection, Population


def _delivery(n: int, reps: int, seed: int):
    """A factored matrix delivery: a dyadic cosine matrix (rows and columns ± equal)."""
    k = 2 * np.pi * np.outer(np.arange(n), np.arange(n)) / n
    w = np.round(256 * (np.cos(k) if seed % 2 else np.sin(k)) * (1 + seed)) / 256
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=w)
    src = Population(id="a", shape={"r": reps, "i": n}, source=True)
    tgt = Population(id="b", shape={"o": n, "r": reps})
    dl = DELIVERY_BUILDERS[MatrixProjection](proj, src, tgt, False)
    assert dl.factors[0] is not None  # the folded product applies
    return dl


def test_events_are_ordered_by_step_then_neuron():
    f = Fired.of_first(np.array([3, -1, 0, 3, 1, 0]), n_steps=5)
    assert [a.tolist() for a in f.events()] == [[2, 5, 4, 0, 3], [0, 0, 1, 3, 3]]
    assert f.events() is f.events()  # built once


@settings(max_examples=60, deadline=None)
@given(n=st.sampled_from([64, 128]), reps=st.integers(1, 3), frames=st.integers(1, 3),
       n_steps=st.integers(2, 40), delay=st.integers(0, 5), data=st.data(),
       seed=st.integers(0, 3))
def test_dense_arrival_features_equal_the_delivered_events(n, reps, frames, n_steps, delay,
                                                           data, seed):
    dl = _delivery(n, reps, seed)
    rng = np.random.default_rng(data.draw(st.integers(0, 2 ** 16)))
    first = rng.integers(-1, n_steps, frames * reps * n)
    first[rng.random(first.size) < data.draw(st.floats(0, 0.9))] = -1
    start = data.draw(st.integers(0, n_steps - 1))
    stop = data.draw(st.integers(start + 1, n_steps))
    fired = Fired.of_first(first, n_steps)
    arr = Arrivals(dl, 0, delay, fired, n_steps)
    flat, arrive = arr.within(start, stop)
    dense = arr.dense_current(start, stop, frames, weighted=True)
    if dense is None:  # too few events for the whole-batch product: the event path serves
        assert flat.size * 16 < frames * reps * n
        return
    ref = dl.current(0, flat, frames, values=(stop - arrive).astype(np.float64))
    np.testing.assert_array_equal(dense, ref)
    # the synaptic-event count from the first-spike steps equals the events' own
    events = Fired.of_events(*fired.events(), n_steps)
    assert _synaptic_events(dl, 0, delay, fired) == _synaptic_events(dl, 0, delay, events)


def test_an_event_record_has_no_dense_current():
    dl = _delivery(64, 1, 0)
    fired = Fired.of_events(np.arange(64), np.zeros(64, np.int64), 4)
    assert Arrivals(dl, 0, 0, fired, 4).dense_current(0, 4, 1, weighted=True) is None
