r"""The spikes of one population as the closed form hands them on: first-spike steps or events.

A population whose neurons spike at most once (fire-once neurons, latency trains) is
kept as its *first-spike steps* ``first`` (flat over ``(frames, size)``, ``-1``: none);
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
"""

from __future__ import annotations

import numpy as np

from backends.reference.order import events_of_first

__all__ = ["Fired"]


class Fired:
    """The spikes of one population over a batch (see the module docstring).

    Build with :meth:`of_first` or :meth:`of_events`; ``first`` is None for the latter.
    """

    __slots__ = ("first", "n_steps", "_events", "_mask")

    def __init__(self, first: np.ndarray | None, n_steps: int,
                 events: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.first, self.n_steps, self._events, self._mask = first, n_steps, events, None

    @classmethod
    def of_first(cls, first: np.ndarray, n_steps: int) -> Fired:
        """At most one spike per neuron: its step, ``-1`` for none."""
        return cls(first, n_steps)

    @classmethod
    def of_events(cls, flat: np.ndarray, step: np.ndarray, n_steps: int) -> Fired:
        """Events ``(flat, step)`` already ordered by step (ties by neuron)."""
        return cls(None, n_steps, (flat, step))

    def events(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, step)`` ordered by step, ties by neuron (built once from ``first``)."""
        if self._events is None:
            self._events = events_of_first(self.first, self.n_steps)
        return self._events

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
