"""Synaptic-event counts of a :class:`~backends.reference.matrix.MatrixDelivery`.

A spike of a source neuron reaches every non-zero weight of its matrix row: its synapse
count.  The simulator's cost figures add these counts per delay class
(:meth:`SynapseCounts.n_events`), or, for a dense matrix with few distinct counts, count
the spikes of each group of sources (:attr:`SynapseCounts.source_synapse_groups`).

Examples
--------
>>> import numpy as np
>>> from backends.reference.matrix import MatrixDelivery
>>> from compiler.snn import MatrixProjection, Population
>>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
...                      produce=("o",), weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
>>> d = MatrixDelivery.build(p, Population(id="a", shape={"i": 2}, source=True),
...                          Population(id="b", shape={"o": 2}))
>>> d.synapses_per_source(0).tolist(), d.n_events(0, np.array([0, 1, 3]))
([1, 2], 5)
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

__all__ = ["MAX_FANOUT_GROUPS", "SynapseCounts"]

#: Distinct per-source synapse counts up to which synaptic events are counted by groups.
MAX_FANOUT_GROUPS = 8


class SynapseCounts:
    """The synapse counts of :class:`~backends.reference.matrix.MatrixDelivery` (a mixin).

    Reads the delivery's ``source_synapses`` and ``col_of`` fields.
    """

    def n_events(self, k: int, events: np.ndarray) -> int:
        """Synaptic events of the events of delay class ``k`` (spikes × synapses reached)."""
        # flat batch indices -> neurons by one vectorised remainder (np.take's mode="wrap"
        # subtracts the size in a loop per index: quadratic in the number of frames), skipped
        # when every event is of the first frame (one pass for the max instead of a division)
        per_source = self.source_synapses[k]
        if events.size and int(events.max()) >= self.src_size:
            events = events % self.src_size
        return int(per_source[events].sum())

    def synapses_per_source(self, k: int) -> np.ndarray:
        """Synapses each source neuron reaches through delay class ``k`` (int64, per neuron)."""
        return self.source_synapses[k]

    @cached_property
    def source_synapse_groups(self) -> tuple[tuple[tuple[int, np.ndarray], ...] | None, ...]:
        """Per delay class, the sources grouped by their synapse count: ``(count, mask)``
        for each non-zero count, or None past :data:`MAX_FANOUT_GROUPS` distinct counts.

        A dense matrix reaches few distinct counts (all of ``n_out``, fewer for a row
        with zeros), so the synaptic events of a spike mask are ``Σ count ·
        popcount(mask ∧ group)`` — bool passes instead of a bool @ int64 product.
        """
        out = []
        for per_source in self.source_synapses:
            counts = np.unique(per_source)
            counts = counts[counts != 0]
            out.append(None if counts.size > MAX_FANOUT_GROUPS else
                       tuple((int(c), per_source == c) for c in counts))
        return tuple(out)
