r"""The spikes of one population as the closed form hands them on: first-spike steps or events.

A population whose neurons spike at most once (fire-once neurons, latency trains) is
kept as its *first-spike steps* ``first`` (flat over ``(frames, size)``, ``-1``: none);
a stream train as its dense *raster* (one boolean row per step, from step ``start``),
or as its integer levels (:class:`~backends.reference.stream_levels.StreamLevels`, the
raster built only when asked for);
any other as *events* ``(flat, step)``, ordered by step and, within a step, by neuron.
The events of a first-spike record are built once, when something asks for them, so a
consumer that can work from ``first`` directly — the silent span's arrival features —
never sorts.

With ``a_i = first_i + d`` the arrival step of neuron ``i``'s spike through a delay
``d``, the *arrival features* of a span ``[s_0, s_1)`` are

.. math::

    f_i = (s_1 - a_i)\,[s_0 \le a_i < s_1] \quad\text{(weighted)}, \qquad
    f_i = [s_0 \le a_i < s_1] \quad\text{(unweighted)},

the dense form of the per-event values the silent span multiplies by the weights.

Examples
--------
>>> import numpy as np
>>> f = Fired.of_first(np.array([2, -1, 0, 2]), n_steps=4)
>>> [a.tolist() for a in f.events()]
[[2, 0, 3], [0, 2, 2]]
>>> f.arrival_features(delay=1, start=1, stop=4, weighted=True).tolist()
[1.0, 0.0, 3.0, 1.0]
>>> r = Fired.of_raster(np.array([[0, 1, 1], [1, 1, 0]], bool), start=2, n_steps=4)
>>> [a.tolist() for a in r.events()], r.first_steps().tolist(), r.counts_before(3).tolist()
([[1, 2, 0, 1], [2, 2, 3, 3]], [3, 2, 2], [0, 1, 1])
"""

from __future__ import annotations

import numpy as np

from backends.reference.order import events_of_first
from backends.reference.stream_levels import StreamLevels

__all__ = ["Fired"]


class Fired:
    """The spikes of one population over a batch (see the module docstring).

    Build with :meth:`of_first` or :meth:`of_events`; ``first`` is None for the latter.
    """

    __slots__ = ("first", "n_steps", "_events", "_mask", "_raster", "_counts", "stream")

    def __init__(self, first: np.ndarray | None, n_steps: int,
                 events: tuple[np.ndarray, np.ndarray] | None = None,
                 raster: tuple[np.ndarray, int] | None = None,
                 stream: StreamLevels | None = None) -> None:
        self.first, self.n_steps, self._events, self._mask = first, n_steps, events, None
        self._raster = raster
        #: The levels of a stream train (the raster follows from them), or None.
        self.stream = stream
        self._counts: dict[int, np.ndarray] = {}

    @property
    def raster(self) -> tuple[np.ndarray, int] | None:
        """``(rows, start)``: row ``r`` of the boolean ``rows`` holds the spikes of step
        ``start + r`` (a stream train's bit planes, built from its levels on first use),
        or None."""
        if self._raster is None and self.stream is not None:
            self._raster = self.stream.raster()
        return self._raster

    @property
    def has_raster(self) -> bool:
        """Whether :attr:`raster` is available (without building it)."""
        return self._raster is not None or self.stream is not None

    @classmethod
    def of_first(cls, first: np.ndarray, n_steps: int) -> Fired:
        """At most one spike per neuron: its step, ``-1`` for none."""
        return cls(first, n_steps)

    @classmethod
    def of_events(cls, flat: np.ndarray, step: np.ndarray, n_steps: int) -> Fired:
        """Events ``(flat, step)`` already ordered by step (ties by neuron)."""
        return cls(None, n_steps, (flat, step))

    @classmethod
    def of_raster(cls, rows: np.ndarray, start: int, n_steps: int) -> Fired:
        """Spikes as boolean ``rows`` (steps × neurons) from step ``start``, within
        ``n_steps``; the events are built only if something asks for them."""
        return cls(None, n_steps, raster=(rows, start))

    @classmethod
    def of_stream(cls, stream: StreamLevels, n_steps: int) -> Fired:
        """A stream train's levels: counts and first steps come from them, the raster is
        built only if something asks for it."""
        return cls(None, n_steps, stream=stream)

    def events(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, step)`` ordered by step, ties by neuron (built once from ``first`` or
        the raster)."""
        if self._events is None and self.raster is not None:
            rows, start = self.raster
            step, flat = np.nonzero(rows)
            self._events = flat.astype(np.int64), (step + start).astype(np.int64)
        if self._events is None:
            self._events = events_of_first(self.first, self.n_steps)
        return self._events

    def counts_before(self, stop: int) -> np.ndarray:
        """Spikes per neuron at steps below ``stop`` (int64; a raster only)."""
        if stop not in self._counts and self.stream is not None:
            self._counts[stop] = self.stream.counts_before(stop)
        if stop not in self._counts:  # asked once per delay class and for the totals
            rows, start = self.raster
            self._counts[stop] = np.count_nonzero(rows[:max(0, stop - start)],
                                                  axis=0).astype(np.int64)
        return self._counts[stop]

    def synaptic_events(self, stop: int, per_source: np.ndarray) -> int:
        """Spikes before ``stop`` × the synapses each reaches (``per_source``, per neuron of
        one frame), summed (a raster or levels only; levels: by column popcounts when
        every bit neuron of a column reaches as many synapses)."""
        if self.stream is not None:
            events = self.stream.synaptic_events(stop, per_source)
            if events is not None:
                return events
        spiked = self.counts_before(stop).reshape(-1, per_source.size)
        return int(spiked.sum(axis=0) @ per_source)

    def first_steps(self) -> np.ndarray:
        """First spike step per neuron, ``-1``: none (a raster or levels only)."""
        if self.stream is not None:
            return self.stream.first_steps()
        rows, start = self.raster
        first = np.full(rows.shape[1], -1, np.int64)
        todo, new = np.ones(rows.shape[1], bool), np.empty(rows.shape[1], bool)
        for r, row in enumerate(rows):  # row passes (an argmax down the columns is slower)
            np.logical_and(row, todo, out=new)
            first[new] = start + r
            todo &= ~row
        return first

    def arrival_features(self, delay: int, start: int, stop: int, weighted: bool) -> np.ndarray:
        """Per neuron (float64): ``stop − a`` (weighted) or 1 for an arrival ``a`` in the
        span, else 0.

        Only for a first-spike record (``first`` is not None).  Arrivals at or after
        ``n_steps`` (beyond the window) never count.  One lookup per neuron in a table
        over the steps (its last entry, read by ``first = −1``, is 0).
        """
        step = np.arange(self.n_steps + 1)
        arrive = step + delay
        inside = (arrive >= start) & (arrive < min(stop, self.n_steps)) & (step < self.n_steps)
        table = np.where(inside, stop - arrive, 0).astype(np.float64) if weighted else (
            inside.astype(np.float64))
        return np.take(table, self.first)

    @property
    def fired_mask(self) -> np.ndarray:
        """``first >= 0``: the neurons that spiked (computed once)."""
        if self._mask is None:
            self._mask = self.first >= 0
        return self._mask

    def arriving(self, delay: int, stop: int) -> np.ndarray:
        """Mask over ``first`` (frames × size) of the spikes arriving before ``stop``."""
        if delay + self.n_steps <= stop:  # every spike (steps are below n_steps)
            return self.fired_mask
        step = np.arange(self.n_steps + 1)
        return np.take((step + delay < stop) & (step < self.n_steps), self.first)
