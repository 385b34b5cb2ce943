r"""A stream train kept as its integer levels: the bit planes are never materialised unless
something asks for events.

A stream code (:mod:`compiler.snn.stream`) sends the level ``q_n`` of sample ``n`` as bit
neurons: neuron ``(frame, pre, b, inner)`` spikes at step ``start + n`` iff bit ``b`` of
``q[n, frame, pre, inner]`` is set.  Everything the closed form needs follows from the
``(steps, frames, pre, inner)`` level array ``q`` directly, ``B`` times smaller than the
boolean raster:

* spikes per neuron before a step: the count of rows ``n`` with bit ``b`` of ``q_n`` set;
* spikes per level column of the bit neurons in a mask ``M`` before a step: the set bits
  ``Σ_n popcount(q_n & M)`` — one pass, enough for spike totals and for synaptic events when
  the bits of ``M`` reach as many synapses from each column;
* first spike step: with ``s_n = q_0 | … | q_n`` (an OR-accumulation down the rows), bit
  ``b`` is first set at row ``m − #\{n : b ∈ s_n\}`` of the ``m`` rows (the rows before it
  lack the bit, every row from it on has it), ``−1`` if never;
* the drive of a projection whose weights are ``2^b V`` on bit ``b``
  (:mod:`backends.reference.resonator_drive`): ``Σ_b [b ∈ q] 2^b V = (q & mask) V``.

Examples
--------
Two samples of one neuron column with 2 bits: levels 2 then 3.

>>> s = StreamLevels(np.array([[[[2]]], [[[3]]]], np.uint16), bits=2, start=1)
>>> s.raster()[0].astype(int).tolist()  # neurons (bit 0, bit 1) per step
[[0, 1], [1, 1]]
>>> s.counts_before(2).tolist(), s.counts_before(9).tolist(), s.first_steps().tolist()
([0, 1], [1, 2], [2, 1])
>>> s.total(9), s.synaptic_events(9, np.array([3, 5])), s.total(9)
(3, 13, 3)
"""

from __future__ import annotations

import numpy as np

__all__ = ["StreamLevels"]

#: Bits counted at once, each in a 9-bit field of a uint64 (counts up to 511).
_SPREAD_BITS, _FIELD_MAX = 7, 511
#: Spread levels per chunk (512 kB of uint64, reused within a call).
_CHUNK_ENTRIES = 1 << 16
_FIELDS = np.arange(_SPREAD_BITS, dtype=np.uint64) * np.uint64(9)
#: ``Σ_k 2^{8k}`` (seven copies of a 7-bit slice) and ``Σ_k 2^{9k}`` (bit ``k`` of copy ``k``).
#: Distinct per-bit synapse profiles counted by masked popcounts before falling back.
_MAX_PROFILES = 4
_COPIES = np.uint64(sum(1 << (8 * k) for k in range(_SPREAD_BITS)))
_FIELD_BITS = np.uint64(sum(1 << (9 * k) for k in range(_SPREAD_BITS)))

class StreamLevels:
    """The levels ``(steps, frames, pre, inner)`` (unsigned ints) of a stream train whose row
    ``n`` is sent at step ``start + n`` as ``bits`` bit neurons per level (see the module
    docstring); neurons are ordered ``(frames, pre, bits, inner)``."""

    __slots__ = ("levels", "bits", "start", "_raster", "_columns")

    def __init__(self, levels: np.ndarray, bits: int, start: int) -> None:
        self.levels, self.bits, self.start = levels, bits, start
        self._raster: np.ndarray | None = None
        self._columns: dict[int, np.ndarray] = {}

    @property
    def inner(self) -> int:
        """Values after the streamed axis (the level columns of one ``pre`` index)."""
        return self.levels.shape[3]

    def raster(self) -> tuple[np.ndarray, int]:
        """``(rows, start)``: the boolean bit planes ``(steps, neurons)`` (built once)."""
        if self._raster is None:
            q = self.levels
            planes = np.empty((*q.shape[:3], self.bits, q.shape[3]), bool)
            bit = np.empty_like(q)
            for b in range(self.bits):  # one plane per bit, written in place
                np.bitwise_and(q, 1 << b, out=bit)
                np.not_equal(bit, 0, out=planes[:, :, :, b, :])
            self._raster = planes.reshape(len(q), int(np.prod(planes.shape[1:])))
        return self._raster, self.start

    def _bit_counts(self, q: np.ndarray) -> np.ndarray:
        """Rows of ``q`` with each bit set, per neuron (flat ``(frames, pre, bits, inner)``).

        Seven bits at a time: a level's 7-bit slice ``v`` times ``Σ_k 2^{8k}`` holds bit
        ``k`` of copy ``k`` at bit ``9k`` (the copies do not overlap: no carries), so
        ``(v · Σ_k 2^{8k}) & Σ_k 2^{9k}`` spreads the bits into 9-bit fields and one sum
        down the rows (at most 511 at a time: no field overflows) counts seven bits at once.
        """
        flat = q.reshape(len(q), int(np.prod(q.shape[1:])))
        n = flat.shape[1]
        counts = np.zeros((n, self.bits), np.int64)
        step = max(1, min(_FIELD_MAX, _CHUNK_ENTRIES // max(1, n)))  # rows per chunk
        buf = np.empty((min(len(flat), step), n), np.uint64)  # reused per chunk
        for lo in range(0, self.bits, _SPREAD_BITS):
            nb = min(_SPREAD_BITS, self.bits - lo)
            for w0 in range(0, len(flat), _FIELD_MAX):  # at most 511 rows per field sum
                total = np.zeros(n, np.uint64)
                for r0 in range(w0, min(len(flat), w0 + _FIELD_MAX), step):
                    rows = flat[r0:min(r0 + step, w0 + _FIELD_MAX)]
                    b = buf[:len(rows)]
                    if lo == 0:  # the low slice: one masking pass
                        np.bitwise_and(rows, (1 << nb) - 1, out=b)
                    else:
                        np.right_shift(rows, lo, out=b)
                        if lo + nb < self.bits:  # bits above the slice (levels < 2^bits)
                            np.bitwise_and(b, np.uint64((1 << nb) - 1), out=b)
                    np.multiply(b, _COPIES, out=b)
                    np.bitwise_and(b, _FIELD_BITS, out=b)
                    total += b.sum(axis=0)
                counts[:, lo:lo + nb] += ((total[:, None] >> _FIELDS[:nb])
                                          & np.uint64(_FIELD_MAX)).astype(np.int64)
        shape = (*q.shape[1:3], q.shape[3], self.bits)
        return counts.reshape(shape).transpose(0, 1, 3, 2).reshape(-1)

    def counts_before(self, stop: int) -> np.ndarray:
        """Spikes per neuron at steps below ``stop`` (int64)."""
        return self._bit_counts(self.levels[:max(0, stop - self.start)])

    def column_counts(self, stop: int, mask: int | None = None) -> np.ndarray:
        """Spikes per level column ``(frames, pre, inner)`` at steps below ``stop`` of the bit
        neurons in ``mask`` (None: all): the set bits of its levels (int64; kept)."""
        if (stop, mask) not in self._columns:
            rows = self.levels[:max(0, stop - self.start)]
            if mask is not None:
                rows = np.bitwise_and(rows, rows.dtype.type(mask))
            most = len(rows) * self.bits  # the largest sum: accumulate in the narrowest type
            acc = np.uint16 if most < 1 << 16 else np.uint32 if most < 1 << 32 else np.uint64
            self._columns[stop, mask] = np.bitwise_count(rows).sum(
                axis=0, dtype=acc).astype(np.int64)
        return self._columns[stop, mask]

    def total(self, stop: int) -> int:
        """Spikes of every neuron at steps below ``stop``: the sum of the masked column
        counts already taken when their masks split the bits, else one popcount pass."""
        masks = [m for (s, m) in self._columns if s == stop and m is not None]
        union = 0
        for m in masks:
            union = union | m if not union & m else -1
        if union == (1 << self.bits) - 1:
            return sum(int(self._columns[stop, m].sum()) for m in masks)
        return int(self.column_counts(stop).sum())

    def synaptic_events(self, stop: int, per_source: np.ndarray) -> int | None:
        """``Σ`` spikes before ``stop`` × ``per_source`` (synapses per neuron of one frame,
        ``(pre, bits, inner)`` order), or None (ask the per-neuron counts) when the bits'
        synapse counts take more than :data:`_MAX_PROFILES` distinct ``(pre, inner)`` profiles.

        Bits with one profile ``g`` (e.g. the low bits of a projection split by weight range)
        count together: their events are ``Σ g · column_counts(stop, mask)``.
        """
        groups = _profiles(per_source, self.levels.shape[2], self.bits, self.inner)
        if groups is None:
            return None
        full = (1 << self.bits) - 1
        return sum(int(np.sum(self.column_counts(stop, None if m == full else m).sum(axis=0)
                              * g)) for g, m in groups)

    def first_steps(self) -> np.ndarray:
        """First spike step per neuron, ``-1``: none."""
        seen = np.empty_like(self.levels)
        for r, row in enumerate(self.levels):  # row passes (down the columns is slower)
            np.bitwise_or(seen[r - 1], row, out=seen[r]) if r else np.copyto(seen[0], row)
        count = self._bit_counts(seen)
        return np.where(count > 0, self.start + len(seen) - count, -1)


#: The latest groupings of :func:`_profiles`, by the identity of the synapse counts (kept
#: with them: a delivery's counts are one array for every frame).
_PROFILES: dict[tuple[int, int, int, int], tuple[np.ndarray, tuple | None]] = {}


def _profiles(per_source: np.ndarray, pre: int, bits: int,
              inner: int) -> tuple[tuple[np.ndarray, int], ...] | None:
    """``((profile, bit mask), …)``: the bits of ``per_source`` (``(pre, bits, inner)``)
    grouped by their ``(pre, inner)`` synapse counts, all-zero bits left out; None past
    :data:`_MAX_PROFILES` groups."""
    key = (id(per_source), pre, bits, inner)
    kept = _PROFILES.get(key)
    if kept is not None and kept[0] is per_source:
        return kept[1]
    per = np.ascontiguousarray(np.moveaxis(per_source.reshape(pre, bits, inner), 1, 0))
    live = per.reshape(bits, -1).any(axis=1)
    groups: dict[bytes, list] = {}  # profile bytes → [profile, bit mask]
    for b in np.flatnonzero(live).tolist():
        group = groups.setdefault(per[b].tobytes(), [per[b], 0])
        group[1] |= 1 << b
    out = (None if len(groups) > _MAX_PROFILES
           else tuple((g, m) for g, m in groups.values()))
    if len(_PROFILES) >= 32:
        _PROFILES.clear()
    _PROFILES[key] = (per_source, out)
    return out
