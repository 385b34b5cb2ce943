r"""Spike delivery: how a batch of spike events becomes input current, per projection kind.

A *delivery* is the simulator's precomputed plan of one projection.  Its
``current(k, events, n_batch, values=None)`` takes spike *events* — flat
indices into a ``(n_batch, *source_shape)`` array, ascending — and returns the
current they produce as a ``(n_batch, *target_shape)`` array, for delay class
``k`` (``delays[k]`` steps).  The batch axis is the frames in step mode and
``steps × frames`` in the closed form, so both engines run the very same
arithmetic.  ``n_events(k, events)`` counts the synaptic events (each spike
times the synapses it reaches); ``weight_nbytes`` is the weight memory.

Kinds: :class:`~backends.reference.matrix.MatrixDelivery` (shared matrix along
named axes) and :class:`~backends.reference.stencil.StencilDelivery` (kernel
correlation), built from a projection's *type* through the explicit
registry :data:`DELIVERY_BUILDERS` (``{MatrixProjection: …, StencilProjection: …}``): the
deliveries are the simulator's, so the compile-path projection classes do not know
them and no ``isinstance`` ladder picks one.

The step engine adds currents straight into a population's state with
:func:`add_current` (a kind's in-place adder from :data:`IN_PLACE_ADDERS`, else
``out += current(...)``), draws the currents of projections fed by an encoder's
spike train from :class:`TrainCurrents` (computed ahead, many steps per batch),
and counts synaptic events once at the end from the per-source-neuron synapse
counts of :func:`synapses_per_source`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from backends.reference.matrix import MatrixDelivery
from backends.reference.row_sums import SEQUENTIAL_MAX, long_run_sums, run_starts
from backends.reference.stencil import StencilDelivery
from compiler.snn.projections import MatrixProjection, StencilProjection

__all__ = ["MatrixDelivery", "StencilDelivery", "Delivery", "DELIVERY_BUILDERS",
           "IN_PLACE_ADDERS", "SYNAPSE_COUNTS", "TRAIN_CURRENTS", "TrainCurrents", "add_current",
           "step_blocks", "synapses_per_source", "FEATURE_CURRENTS"]

Delivery = MatrixDelivery | StencilDelivery

#: Delivery builders by projection type: ``(projection, source, target, integer) -> delivery``.
DELIVERY_BUILDERS: dict[type, Callable[..., Delivery]] = {
    MatrixProjection: MatrixDelivery.build,
    StencilProjection: StencilDelivery.build,
}

#: In-place adders by delivery type, ``(delivery, k, events, n_batch, out) -> None``; a type
#: missing here is added densely (``out += current(...)``).
IN_PLACE_ADDERS: dict[type, Callable[..., None]] = {MatrixDelivery: MatrixDelivery.add_to}

#: Dense-feature currents by delivery type: ``(applies(delivery, k, n_events, n_batch),
#: current(delivery, k, feature, n_batch))`` (:meth:`MatrixDelivery.feature_current`); a
#: type missing here always delivers events.  ``current`` returns a new array, which the
#: caller may keep and write (the silent span sums into the first one).
FEATURE_CURRENTS: dict[type, tuple[Callable[..., bool], Callable[..., np.ndarray]]] = {
    MatrixDelivery: (MatrixDelivery.dense_for, MatrixDelivery.feature_current),
}

#: Synapses per source neuron by delivery type, ``(delivery, k) -> int64 (source size,)``.
SYNAPSE_COUNTS: dict[type, Callable[..., np.ndarray]] = {
    MatrixDelivery: MatrixDelivery.synapses_per_source,
    StencilDelivery: lambda d, k: d.synapses[k].astype(np.int64),
}


def _add_dense(delivery: Delivery, k: int, events: np.ndarray, n_batch: int,
               out: np.ndarray) -> None:
    out += delivery.current(k, events, n_batch).reshape(-1)


def add_current(
    delivery: Delivery, k: int, events: np.ndarray, n_batch: int, out: np.ndarray
) -> None:
    """``out += delivery.current(k, events, n_batch)`` (flat ``out``), in place.

    Parameters
    ----------
    delivery : Delivery
        The projection's delivery.
    k : int
        Delay class.
    events : ndarray of int
        Flat source indices into ``(n_batch, *source_shape)``, ascending.
    n_batch : int
        Batch rows.
    out : ndarray
        Flat ``(n_batch * target size)`` array of the delivery's dtype.

    Notes
    -----
    An in-place adder touches only the target rows the events reach, so the
    result is bit-identical to ``out + current`` wherever ``out`` holds no
    negative zero (``x + 0.0`` differs from ``x`` only for ``x = -0.0``).

    Examples
    --------
    >>> from compiler.snn import Population, StencilProjection
    >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
    ...                       kernel=np.array([1.0, 0.0, 2.0]), edge=("clip",))
    >>> a = Population(id="a", shape={"r": 4}, source=True)
    >>> d = StencilDelivery.build(k, a, Population(id="b", shape={"r": 4}))
    >>> out = np.ones(4)
    >>> add_current(d, 0, np.array([2]), 1, out)
    >>> out.tolist()
    [1.0, 3.0, 1.0, 2.0]
    """
    IN_PLACE_ADDERS.get(type(delivery), _add_dense)(delivery, k, events, n_batch, out)


def synapses_per_source(delivery: Delivery, k: int) -> np.ndarray:
    """Synapses each source neuron reaches through delay class ``k`` (int64, source size).

    A spike's synaptic events are this count (what ``n_events`` sums per event).

    Examples
    --------
    >>> from compiler.snn import MatrixProjection, Population
    >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
    ...                      produce=("o",), weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
    >>> d = MatrixDelivery.build(p, Population(id="a", shape={"i": 2}, source=True),
    ...                          Population(id="b", shape={"o": 2}))
    >>> synapses_per_source(d, 0).tolist()
    [1, 2]
    """
    return SYNAPSE_COUNTS[type(delivery)](delivery, k)


#: Whether a delivery's rows are independent of the batch (its currents can be computed for
#: many steps at once), by delivery type; types missing here never are.
TRAIN_CURRENTS: dict[type, Callable[..., bool]] = {
    MatrixDelivery: lambda d: d.rows_independent,
}

#: Default cap on one block of precomputed train currents (bytes): cache-sized; measured
#: best between 128 KiB and 1 MiB on the 256-point S-FT benchmark.
TRAIN_BLOCK_BYTES = 1 << 20


def step_blocks(bounds: np.ndarray, max_events: int) -> list[int]:
    """First steps of consecutive blocks of whole steps holding at most ``max_events`` events.

    ``bounds[t]`` is the number of events before step ``t`` (``n_steps + 1``
    entries); a step with more events than ``max_events`` is a block of its own.

    Examples
    --------
    >>> step_blocks(np.array([0, 2, 3, 3, 7, 8]), max_events=3)
    [0, 3, 4]
    """
    n_steps, starts, t = bounds.size - 1, [], 0
    while t < n_steps:
        starts.append(t)
        stop = int(np.searchsorted(bounds, bounds[t] + max_events, side="right")) - 1
        t = min(max(stop, t + 1), n_steps)
    return starts


class TrainCurrents:
    r"""The currents one delivery class draws from a known spike train, computed ahead.

    The spikes of the train at step ``s`` arrive at ``a = s + d``.  All arrivals
    form one batch of ``n_steps × n_frames`` rows (batch row ``a·n_frames + frame``,
    then repetitions), split into blocks of whole steps holding at most
    ``block_bytes`` of gathered weight rows.  Everything about the batch that does
    not depend on the weights — runs of equal rows, their heads, the tails level by
    level, per block — is indexed once, for all blocks together; a block then costs
    two gathers and a few slice additions, with the arithmetic of
    :func:`~backends.reference.row_sums.grouped_sums` (``np.add.reduceat``'s), so every
    row's current is bit for bit the one a delivery of step ``a`` alone gives
    (the delivery's rows are independent, :data:`TRAIN_CURRENTS`).

    Parameters
    ----------
    delivery : MatrixDelivery
        A delivery with independent rows.
    k, d : int
        Delay class and its delay.
    flat, steps : ndarray of int
        The train's spikes (flat index into ``(n_frames, source size)``, step),
        ordered by step, then index.
    n_frames, n_steps : int
        Frames in the batch, steps per frame.
    block_bytes : int
        Cap on one block's gathered rows (a block holds at least one step).
    paired : bool
        Where the weights' columns pair as ``(y, −y)``
        (:attr:`MatrixDelivery.paired_halves`), gather and sum the even halves only;
        :meth:`at` then returns those halves, for :attr:`add_rows` (the delivery's
        ``add_paired_rows``) to add — the same bits in the target as the full rows.

    Examples
    --------
    >>> from compiler.snn import MatrixProjection, Population
    >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
    ...                      produce=("o",), weights=np.array([[1.0], [2.0]]))
    >>> dl = MatrixDelivery.build(p, Population(id="a", shape={"i": 2}, source=True),
    ...                           Population(id="b", shape={"o": 1}))
    >>> tc = TrainCurrents(dl, 0, 1, np.array([0, 1, 1]), np.array([0, 0, 2]), n_frames=1,
    ...                    n_steps=4)
    >>> tc.at(0) is None, [a.tolist() for a in tc.at(1)], [a.tolist() for a in tc.at(3)]
    (True, [[0], [[3.0]]], [[0], [[2.0]]])
    """

    def __init__(self, delivery: MatrixDelivery, k: int, d: int, flat: np.ndarray,
                 steps: np.ndarray, n_frames: int, n_steps: int,
                 block_bytes: int = TRAIN_BLOCK_BYTES, paired: bool = False) -> None:
        self.delivery, self.k = delivery, k
        half = delivery.paired_halves[k] if paired else None
        #: The gathered table: the weights, or their even half (``paired``).
        self.table = delivery.weights[k] if half is None else half
        #: ``add_rows(rows, currents, out)`` for what :meth:`at` returns.
        self.add_rows = delivery.add_rows if half is None else delivery.add_paired_rows
        per_step = n_frames * delivery.n_reps
        keep = steps + d < n_steps
        rows, cols = delivery.event_rows(flat[keep], n_frames)
        rows = (steps[keep] + d) * per_step + rows  # one batch of all steps, step-major
        if rows.size > 1 and (rows[1:] < rows[:-1]).any():  # keeps each row's events in order
            order = np.argsort(rows, kind="stable")
            rows, cols = rows[order], cols[order]
        self._cols = cols
        starts = run_starts(rows)
        counts = np.diff(np.append(starts, rows.size))
        self._heads = cols[starts]
        run_step, self._run_rows = np.divmod(rows[starts], per_step)  # step, row within it
        self._step_runs = np.searchsorted(run_step, np.arange(n_steps + 1))
        # blocks of whole steps: at most max_events arrivals each (at least one step)
        event_bounds = np.searchsorted(rows // per_step, np.arange(n_steps + 1))
        dtype = np.int64 if delivery.integer else np.float64
        block_starts = step_blocks(
            event_bounds, max(1, block_bytes // (self.table.shape[1] * np.dtype(dtype).itemsize)))
        n_blocks = len(block_starts)
        self._block_of_step = np.repeat(np.arange(n_blocks),
                                        np.diff(np.append(block_starts, n_steps)))
        self._block_runs = self._step_runs[np.append(block_starts, n_steps)].tolist()
        run_block = self._block_of_step[run_step]
        # tails (addends 2..m of runs of m > 1), per block longest run first, level by level
        multi = (counts > 1).nonzero()[0]
        owner = multi[np.lexsort((-counts[multi], run_block[multi]))]
        length = counts[owner]
        levels = np.minimum(length, SEQUENTIAL_MAX) - 1  # tail addends summed level by level
        entry_owner = np.repeat(np.arange(owner.size), levels)
        level = np.arange(entry_owner.size) - np.repeat(np.cumsum(levels) - levels, levels) + 1
        entry_block = run_block[owner][entry_owner]
        order = np.argsort(entry_block * SEQUENTIAL_MAX + level, kind="stable")
        self._tails = cols[starts[owner][entry_owner] + level][order]
        per_level = np.bincount(entry_block * SEQUENTIAL_MAX + level,
                                minlength=n_blocks * SEQUENTIAL_MAX)
        self._levels = per_level.reshape(n_blocks, SEQUENTIAL_MAX)[:, 1:].tolist()
        self._block_entries = np.searchsorted(entry_block[order],
                                              np.arange(n_blocks + 1)).tolist()
        self._block_owners = np.searchsorted(run_block[owner], np.arange(n_blocks + 1)).tolist()
        self._owner_local = owner - self._step_runs[np.asarray(block_starts)][run_block[owner]]
        # runs longer than SEQUENTIAL_MAX (numpy's pairwise sum): first of their block's owners
        self._deep = np.bincount(run_block[owner][length > SEQUENTIAL_MAX],
                                 minlength=n_blocks).tolist()
        self._owner_span = np.stack([starts[owner], length], axis=1)
        per_block = np.diff(event_bounds[np.append(block_starts, n_steps)])
        most = int(per_block.max()) if n_blocks else 0
        self._workspace = np.empty((most, self.table.shape[1]), dtype)  # reused: no faults
        self._block, self._sums = -1, self._workspace

    def at(self, t: int) -> tuple[np.ndarray, np.ndarray] | None:
        """``(rows, currents)`` arriving at step ``t`` (for ``add_rows``), or None if none do."""
        lo, hi = self._step_runs[t], self._step_runs[t + 1]
        if lo == hi:
            return None
        block = self._block_of_step[t]
        if block != self._block:
            self._compute(block)
        first = self._block_runs[block]
        return self._run_rows[lo:hi], self._sums[lo - first:hi - first]

    def _compute(self, block: int) -> None:
        """The currents of every run of ``block``: heads plus level-summed tails."""
        table = self.table
        r0, r1 = self._block_runs[block], self._block_runs[block + 1]
        sums = np.take(table, self._heads[r0:r1], axis=0, out=self._workspace[:r1 - r0])
        e0, e1 = self._block_entries[block], self._block_entries[block + 1]
        if e1 > e0:
            tails = np.take(table, self._tails[e0:e1], axis=0,
                            out=self._workspace[r1 - r0:r1 - r0 + e1 - e0])
            counts = self._levels[block]
            tail, end = tails[:counts[0]], counts[0]
            for n in counts[1:]:
                if not n:
                    break
                tail[:n] += tails[end:end + n]
                end += n
            o0, o1 = self._block_owners[block], self._block_owners[block + 1]
            owners = self._owner_local[o0:o1]
            sums[owners] += tail
            deep = self._deep[block]
            if deep:  # long runs: numpy's own pairwise order
                first, length = self._owner_span[o0:o0 + deep].T
                sums[owners[:deep]] = long_run_sums(
                    lambda at: np.take(table, self._cols[at], axis=0), first, length)
        self._block, self._sums = block, sums
