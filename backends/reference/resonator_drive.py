r"""The resonators' drive in the closed form: folded to one complex number per resonator, and
computed once per repetition when every bin receives the same input.

The step engine adds each step's synaptic current into the four compartments of every
resonator and folds it to ``d = (I_0 − I_1) + i(I_2 − I_3)``
(:mod:`backends.reference.resonator`).  The ``resonator`` motif feeds each sample to every
bin through one fan-out synapse per bit and part, so the weight matrix of each
projection is the same for every index of the resonator axis: the drive is then a
function of the repetition alone, and the closed form computes it for one bin — a
``(steps · frames · repetitions) × n_in`` count table (a stream train's raster rows as
they are, else one ``bincount`` of the events) times the ``n_in × n_out / K`` slice of the
weights (float32 where every sum is a whole number below ``2**24``) — instead of the
``K``-times larger histogram of every compartment.  From a stream source whose weights
are ``2^b`` times one matrix on bit ``b`` (the motif's), the count table is never built:
the product is the levels' own (:mod:`backends.reference.level_drive`), one per stream and
delay however many projections split its bits.

The sums are those of the step engine whenever they are exact: int64 arithmetic, or
whole-number weights whose row sums stay below ``2**52`` (each neuron spikes at most once
per step, so a count is 0 or 1).  :func:`shared_drive` says None otherwise, and the
caller builds the full histogram (:func:`backends.reference.spans.drive`).

Examples
--------
A stream source of two bit neurons (levels 1 and 2) fanned out to three bins; both bits
spike at step 0, the second alone at step 1:

>>> import numpy as np
>>> from backends.reference import build_plan
>>> from backends.reference.fired import Fired
>>> from backends.reference.spans import Arrivals
>>> from compiler.snn import Encoder, MatrixProjection, Population, SpikingNetwork
>>> from compiler.snn.resonator import ResonatorParams
>>> from compiler.snn.stream import StreamCode
>>> b, k = (a.ravel() for a in np.meshgrid(np.arange(2), np.arange(3), indexing="ij"))
>>> net = SpikingNetwork(name="n", n_steps=2, populations=[
...     Population(id="in", shape={"bit": 2}, source=True),
...     Population(id="out", shape={"k": 3, "part": 4},
...                params=ResonatorParams(axis="k", cos=(1.0,) * 3, sin=(0.0,) * 3))],
...     projections=[MatrixProjection(id="w", source="in", target="out", contract=("bit",),
...                  produce=("k", "part"), rows=b, cols=k * 4, values=2.0 ** b,
...                  n_in_out=(2, 12))],
...     encoders=[Encoder(port="x", population="in",
...                       code=StreamCode(axis="n", length=2, inner=1, bits=2, x_max=3.0))])
>>> plan = build_plan(net)
>>> fired = Fired.of_events(np.array([0, 1, 1]), np.array([0, 0, 1]), 2)
>>> arr = [Arrivals(plan.deliveries["w"], 0, 0, fired, 2)]
>>> shared_drive(plan, "out", arr, 1, 0, 2).tolist()  # (steps, frames, k = 1): one bin
[[[(3+0j)]], [[(2+0j)]]]
"""

from __future__ import annotations

import weakref
from math import prod

import numpy as np
import scipy.sparse as sp

from backends.reference.level_drive import LevelWeights, level_current, level_weights
from backends.reference.matrix import MatrixDelivery
from backends.reference.plan import SimPlan
from compiler.snn.resonator import N_COMPARTMENTS

__all__ = ["shared_drive", "fold", "SharedWeights"]

#: Largest weight matrix (entries) examined for a shared drive (larger: the full histogram).
_MAX_ENTRIES = 1 << 24
#: Bytes of one count table (steps are cut into blocks below it).
_COUNT_BYTES = 8 << 20

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class SharedWeights:
    """One delay class of a delivery, reduced to a single index of the resonator axis.

    ``weights`` is ``(n_in, n_out / K)`` float64 (exact: whole numbers, or float
    arithmetic), ``block`` the reduced ``(repetitions…, produce…)`` shape and ``to_target``
    the delivery's permutation into target order.
    """

    __slots__ = ("weights", "block", "to_target", "dense", "order", "weights32", "_levels")

    def __init__(self, weights: np.ndarray, block: tuple[int, ...],
                 to_target: tuple[int, ...], dense: bool = False,
                 order: np.ndarray | None = None) -> None:
        self.weights, self.block, self.to_target = weights, block, to_target
        #: Every source neuron has its own (repetition, input row) slot: a raster's rows are
        #: the count table, its columns taken in ``order`` (None: already in slot order).
        self.dense, self.order = dense, order
        #: The weights in float32 where every sum of them is a whole number below 2^24 (exact
        #: in single precision: half the bytes per count), else None.
        whole = np.array_equal(weights, np.rint(weights))
        small = np.abs(weights).sum(axis=0).max(initial=0.0) < 2.0 ** 24
        self.weights32 = weights.astype(np.float32) if whole and small else None
        self._levels: dict[tuple[int, int, int], LevelWeights | None] = {}

    def by_levels(self, n_reps: int, bits: int, inner: int) -> LevelWeights | None:
        """The weights factored over the levels of a stream source of ``bits`` bits and
        ``inner`` values after the streamed axis (dense slots only), or None (computed once)."""
        key = (n_reps, bits, inner)
        if key not in self._levels:
            self._levels[key] = level_weights(self.weights, self.order, n_reps, bits, inner)
        return self._levels[key]


def _reduce(plan: SimPlan, dl, k: int, axis: str) -> SharedWeights | None:
    """The reduced weights of class ``k`` of ``dl``, or None (not shared along ``axis``,
    not a matrix, too large, or sums that may round)."""
    if not isinstance(dl, MatrixDelivery):
        return None
    proj = next(p for p in plan.network.projections if p.id == dl.id)
    if axis not in proj.produce or dl.weights[k].shape[0] * dl.weights[k].shape[1] > _MAX_ENTRIES:
        return None
    w = dl.weights[k]
    w = np.asarray(w.toarray() if sp.issparse(w) else w, np.float64)
    n_rep_axes = len(dl.block_shape) - len(proj.produce)
    produce = dl.block_shape[n_rep_axes:]
    at = proj.produce.index(axis)
    grid = w.reshape(w.shape[0], *produce)
    one = np.take(grid, [0], axis=1 + at)
    if not np.array_equal(grid, np.broadcast_to(one, grid.shape)):
        return None
    whole = plan.integer or bool(np.all(one == np.rint(one)))
    if whole and np.abs(one).sum(axis=0).max(initial=0.0) >= 2.0 ** 52:
        return None  # a row sum might round
    if not whole and _fixed_point(plan, dl.target):
        return None  # fractional weights: the fixed-point rounding needs the step's sums
    block = (*dl.block_shape[:n_rep_axes], *(1 if i == at else s for i, s in enumerate(produce)))
    slot = dl.rep_of * dl.n_in + dl.col_of
    dense = slot.size == dl.n_reps * dl.n_in and np.bincount(slot).max(initial=0) <= 1
    order = np.argsort(slot) if dense else None
    if dense and np.array_equal(order, np.arange(slot.size)):
        order = None
    return SharedWeights(np.ascontiguousarray(one.reshape(w.shape[0], -1)), block, dl.to_target,
                         dense, order)


def _fixed_point(plan: SimPlan, pid: str) -> bool:
    return getattr(plan.neurons[pid], "coef_bits", 0) > 0


def _shared(plan: SimPlan, dl, k: int, axis: str) -> SharedWeights | None:
    per = _CACHE.setdefault(dl, {})
    if (k, axis) not in per:
        per[(k, axis)] = _reduce(plan, dl, k, axis)
    return per[(k, axis)]


def shared_drive(plan: SimPlan, pid: str, arrivals: list, n_frames: int, s0: int,
                 s1: int) -> np.ndarray | None:
    """The complex drive of steps ``[s0, s1)`` at one index of the resonator axis, or None.

    Returns ``(s1 − s0, n_frames, *dims)`` complex128, ``dims`` the target's shape without
    ``part`` and with the resonator axis of size 1; None when some incoming projection is
    not shared along the axis (see the module docstring).
    """
    pop = plan.populations[pid]
    axis = plan.network.population[pid].params.axis
    reduced = [(_shared(plan, a.delivery, a.k, axis), a) for a in arrivals]
    if any(r is None for r, _ in reduced):
        return None
    dims = tuple(1 if a == axis else s for a, s in zip(pop.axes, pop.dims, strict=True))
    n_t = s1 - s0
    out = np.zeros((n_t * n_frames, *dims[:-1]), np.complex128)  # folded contributions
    total = None  # compartment currents of the others, folded at the end
    for red, arr, lw in _merge_levels(reduced):
        if (lw is not None and lw.folded is not None and red.block[-1] == N_COMPARTMENTS
                and red.to_target[-1] == len(red.block) - 1):  # compartments last
            _add_level_drive(out, red, lw, arr, n_frames, s0, s1, folded=True)
            continue
        if total is None:
            total = np.zeros((n_t * n_frames, *dims))
        if lw is not None:
            _add_level_drive(total, red, lw, arr, n_frames, s0, s1)
        else:
            _add_drive(total, red, arr, n_frames, s0, s1)
    if total is not None:  # whole sums: (ΣI_0 − ΣI_1) is Σ(I_0 − I_1), exactly
        out += fold(total)
    return out.reshape(n_t, n_frames, *dims[:-1])


def _merge_levels(reduced: list) -> list:
    """``(red, arr, lw)`` per arrival class, ``lw`` its factorisation over a stream source's
    levels (None: the raster or events); classes from the same stream with the same delay,
    layout and ``V`` but disjoint bits (the bit groups of one motif) merged into one."""
    out = []
    for red, arr in reduced:
        stream = arr.fired.stream if red.dense else None
        n_reps = prod(red.block) // red.weights.shape[1]
        lw = None if stream is None else red.by_levels(n_reps, stream.bits, stream.inner)
        for i, (red0, arr0, lw0) in enumerate(out):
            if (lw is not None and lw0 is not None and arr0.fired is arr.fired
                    and arr0.delay == arr.delay and red0.block == red.block
                    and red0.to_target == red.to_target
                    and (both := lw0.merged(lw)) is not None):
                out[i] = (red0, arr0, both)
                break
        else:
            out.append((red, arr, lw))
    return out


def _add_drive(total: np.ndarray, red: SharedWeights, arr, n_frames: int, s0: int,
               s1: int) -> None:
    """``total += `` the current of ``arr``'s events in ``[s0, s1)`` through ``red`` (the
    raster's rows or the events counted)."""
    dl = arr.delivery
    n_reps, n_in = prod(red.block) // red.weights.shape[1], dl.n_in
    per_step = n_frames * n_reps * n_in
    chunk = max(1, _COUNT_BYTES // (8 * per_step))
    if red.dense and arr.fired.has_raster:
        _add_raster_drive(total, red, arr, n_frames, s0, s1, chunk)
        return
    flat, arrive = arr.within(s0, s1)
    bounds = np.searchsorted(arrive, np.arange(s0, s1 + chunk, chunk))
    for c, t0 in enumerate(range(s0, s1, chunk)):
        t1 = min(s1, t0 + chunk)
        lo, hi = bounds[c], bounds[c + 1]
        if lo == hi:
            continue
        f, i = (0, flat[lo:hi]) if n_frames == 1 else np.divmod(flat[lo:hi], dl.src_size)
        row = (arrive[lo:hi] - t0) * n_frames + f
        row *= n_reps
        row += dl.rep_of[i]
        row *= n_in
        row += dl.col_of[i]
        counts = np.bincount(row, minlength=(t1 - t0) * per_step).reshape(-1, n_in)
        current = (counts @ red.weights).reshape((t1 - t0) * n_frames, *red.block)
        current = current.transpose(0, *(1 + a for a in red.to_target))
        total[(t0 - s0) * n_frames:(t1 - s0) * n_frames] += current


def _add_level_drive(total: np.ndarray, red: SharedWeights, lw, arr, n_frames: int, s0: int,
                     s1: int, folded: bool = False) -> None:
    """:func:`_add_drive` from a stream train's levels (:mod:`backends.reference.level_drive`;
    arrivals at ``n_steps`` or later cut, as for the raster); ``folded``: ``total`` is the
    complex drive (no compartment axis) and the product is folded already."""
    stream = arr.fired.stream
    first = stream.start + arr.delay  # the arrival step of level row 0
    lo, hi = max(s0, first), min(s1, first + len(stream.levels), arr.n_steps)
    if lo >= hi:
        return
    current = level_current(stream.levels, lw, lo - first, hi - first, n_frames, folded)
    block, order = red.block, red.to_target
    if folded:
        current, block, order = current.view(np.complex128), block[:-1], order[:-1]
    current = current.reshape((hi - lo) * n_frames, *block)
    total[(lo - s0) * n_frames:(hi - s0) * n_frames] += current.transpose(
        0, *(1 + a for a in order))


def _add_raster_drive(total: np.ndarray, red: SharedWeights, arr, n_frames: int, s0: int,
                      s1: int, chunk: int) -> None:
    """:func:`_add_drive` from a raster: its rows in slot order are the count table (the
    events of one step are the row's set bits; a spike arriving at ``n_steps`` or later is
    cut, as :class:`~backends.reference.spans.Arrivals` cuts it)."""
    rows, start = arr.fired.raster
    first = start + arr.delay  # the arrival step of row 0
    lo, hi = max(s0, first), min(s1, first + len(rows), arr.n_steps)
    n_in = arr.delivery.n_in
    for t0 in range(lo, hi, chunk):
        t1 = min(hi, t0 + chunk)
        part = rows[t0 - first:t1 - first].reshape(t1 - t0, n_frames, -1)
        if red.order is not None:
            part = np.take(part, red.order, axis=2)
        w = red.weights if red.weights32 is None else red.weights32
        counts = part.reshape(-1, n_in).astype(w.dtype)
        current = (counts @ w).reshape((t1 - t0) * n_frames, *red.block)
        current = current.transpose(0, *(1 + a for a in red.to_target))
        total[(t0 - s0) * n_frames:(t1 - s0) * n_frames] += current


def fold(current: np.ndarray) -> np.ndarray:
    """``(I_0 − I_1) + i(I_2 − I_3)`` over a trailing compartment axis (complex128).

    Examples
    --------
    >>> fold(np.array([[3, 1, 0, 2]])).tolist()
    [(2-2j)]
    """
    out = np.empty(current.shape[:-1], np.complex128)
    np.subtract(current[..., 0], current[..., 1], out=out.real)
    np.subtract(current[..., 2], current[..., 3], out=out.imag)
    return out
