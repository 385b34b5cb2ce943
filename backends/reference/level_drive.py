r"""The resonators' shared drive from a stream train's levels, without its bit planes.

A projection from the bit neurons of a stream code (:mod:`compiler.snn.stream`) to the
resonators weights bit ``b`` of a level by ``2^b`` (``q = Σ_b 2^b [b ∈ q]``), so its count
table times its weights (:mod:`backends.reference.resonator_drive`) is a product of the
levels themselves.  With the reduced weights ``W`` (one row per input column ``(c, b)``:
``c`` a level column, ``b`` a bit) factoring as ``W_{(c,b)} = 2^b V_c`` on the bits ``b``
whose rows are not zero (``mask_c``, the others' rows zero),

.. math:: \sum_b [b ∈ q_c]\, W_{(c,b)} = (q_c \mathbin{\&} \mathrm{mask}_c)\, V_c ,

one product of the ``(steps · frames · repetitions) × C`` masked levels with the
``C × n_out`` matrix ``V`` instead of the ``B``-times wider raster.  It is exact, and so the
step engine's sum, when ``V`` is whole and ``(2^B − 1) Σ_c |V_c| < 2^{52}``;
:func:`level_weights` says None otherwise (fractional weights, rows that do not factor,
columns whose bits do not line up with the levels), and the caller multiplies the raster.

Examples
--------
Four bit neurons (2 bits × 2 level columns, ``inner = 2``), each repetition's two columns
weighted ``2^b·(1, −1)`` into one output:

>>> w = np.array([[1.0], [-1.0], [2.0], [-2.0]])  # input column (b, c): rows b·2 + c
>>> lw = level_weights(w, None, n_reps=1, bits=2, inner=2)
>>> lw.cols.tolist(), lw.mask.tolist(), lw.weights.ravel().tolist()
([[0, 1]], [3, 3], [1.0, -1.0])
>>> q = np.array([[[[3, 1]]]], np.uint16)  # one step, frame and pre index: levels 3 and 1
>>> level_current(q, lw, 0, 1, 1).tolist()  # 3·1 + 1·(−1)
[[2.0]]
"""

from __future__ import annotations

import numpy as np

__all__ = ["LevelWeights", "level_weights", "level_current"]

#: Masked levels of one product (steps are cut into blocks below it: 1 MiB as float64).
_LEVEL_ENTRIES = 1 << 17


class LevelWeights:
    """The factored weights of one delay class: the level column ``cols[rep, c]`` of each
    repetition, the bits ``mask[c]`` it sends and ``weights`` ``V`` (``C × n_out``)."""

    __slots__ = ("cols", "mask", "weights", "bits", "full", "identity", "key", "folded")

    def __init__(self, cols: np.ndarray, mask: np.ndarray, weights: np.ndarray,
                 bits: int) -> None:
        self.cols, self.mask, self.weights, self.bits = cols, mask, weights, bits
        #: Every column sends every bit (no masking needed).
        self.full = bool(np.all(mask == (1 << bits) - 1))
        #: The columns are the levels' own order (no gather needed).
        self.identity = bool(np.array_equal(cols.reshape(-1), np.arange(cols.size)))
        #: Equal for weights that differ in their masks alone (:meth:`merged`).
        self.key = (cols.shape, weights.shape, bits, cols.tobytes(), weights.tobytes())
        #: ``V`` folded over trailing compartments ``(I_0 − I_1) + i(I_2 − I_3)``, as
        #: interleaved (real, imaginary) columns: the product is the complex drive itself.
        #: None unless whole sums below ``2^52`` (or the columns are not in fours).
        self.folded = _folded(weights, bits)

    def merged(self, other: LevelWeights) -> LevelWeights | None:
        """One factorisation sending the bits of both (same columns and ``V``, disjoint
        masks: ``(q & m_1)V + (q & m_2)V = (q & (m_1 | m_2))V``), or None."""
        if self.key != other.key or np.any(self.mask & other.mask):
            return None
        return LevelWeights(self.cols, self.mask | other.mask, self.weights, self.bits)


def level_weights(weights: np.ndarray, order: np.ndarray | None, n_reps: int, bits: int,
                  inner: int) -> LevelWeights | None:
    """Factor reduced weights ``(n_in, n_out)`` over a stream source, or None.

    Parameters
    ----------
    weights : ndarray
        One delay class's reduced weights (float64), rows the input columns.
    order : ndarray or None
        The source neuron of each ``(repetition, input column)`` slot (flat; None: slot
        order is neuron order).
    n_reps : int
    bits, inner : int
        The stream code's bits and values after the streamed axis: source neuron
        ``(pre, b, i)`` of a frame sends bit ``b`` of level column ``pre · inner + i``.
    """
    n_in = weights.shape[0]
    neuron = (np.arange(n_reps * n_in) if order is None else order).reshape(n_reps, n_in)
    bit = (neuron // inner) % bits
    col = (neuron // (bits * inner)) * inner + neuron % inner
    if not np.array_equal(bit, np.broadcast_to(bit[0], bit.shape)):
        return None
    bit = bit[0]
    _, first, c_of = np.unique(col[0], return_index=True, return_inverse=True)
    cols = col[:, first]
    if (not np.array_equal(col, cols[:, c_of])
            or np.unique(c_of * bits + bit).size < n_in):  # each (column, bit) once
        return None
    scaled = weights / (2.0 ** bit)[:, None]
    live = np.any(weights != 0, axis=1)
    v = np.zeros((first.size, weights.shape[1]))
    v[c_of[live]] = scaled[live]
    mask = np.zeros(first.size, np.int64)
    np.bitwise_or.at(mask, c_of[live], 1 << bit[live])
    exact = (np.array_equal(v[c_of[live]], scaled[live]) and np.array_equal(v, np.rint(v))
             and ((1 << bits) - 1) * np.abs(v).sum(axis=0).max(initial=0.0) < 2.0 ** 52)
    return LevelWeights(cols, mask, v, bits) if exact else None


def _folded(v: np.ndarray, bits: int) -> np.ndarray | None:
    if v.shape[1] % 4:
        return None
    parts = v.reshape(v.shape[0], -1, 4)
    folded = np.stack([parts[..., 0] - parts[..., 1], parts[..., 2] - parts[..., 3]],
                      axis=-1).reshape(v.shape[0], -1)
    exact = ((1 << bits) - 1) * np.abs(folded).sum(axis=0).max(initial=0.0) < 2.0 ** 52
    return folded if exact else None


def level_current(levels: np.ndarray, lw: LevelWeights, r0: int, r1: int,
                  n_frames: int, folded: bool = False) -> np.ndarray:
    """The current ``(steps · frames · repetitions, n_out)`` of level rows ``[r0, r1)``
    (``levels``: ``(rows, frames, pre, inner)``) through ``lw``, float64; ``folded``: through
    :attr:`LevelWeights.folded` (``n_out / 4`` complex columns as float pairs)."""
    m = r1 - r0
    n_reps, n_cols = lw.cols.shape
    weights = lw.folded if folded else lw.weights
    out = np.empty((m * n_frames * n_reps, weights.shape[1]))
    chunk = max(1, _LEVEL_ENTRIES // max(1, n_frames * lw.cols.size))
    per_row = n_frames * n_reps
    for a in range(r0, r1, chunk):
        b = min(r1, a + chunk)
        q = levels[a:b].reshape(b - a, n_frames, -1)
        if lw.identity and q.shape[2] == lw.cols.size:
            picked = q.reshape(-1, n_cols)
        else:
            picked = np.take(q, lw.cols.reshape(-1), axis=2).reshape(-1, n_cols)
        if not lw.full:
            picked = picked & lw.mask.astype(picked.dtype)
        np.matmul(picked.astype(np.float64), weights,
                  out=out[(a - r0) * per_row:(b - r0) * per_row])
    return out
