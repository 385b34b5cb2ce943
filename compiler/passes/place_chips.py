r"""Chips of a placement: group the used cores into chips so that heavy spike traffic stays on-chip.

The placer fills cores (per-core budgets); which chip a core sits on changes no budget,
only which messages cross a chip boundary.  So chips are assigned afterwards, as a
partition of the used cores into :math:`k = \lceil n / C \rceil` chips of ``C =
cores_per_chip`` cores (all full but the last), minimising the inter-chip messages

.. math:: \text{cut} = \sum_{a, b:\ \text{chip}(a) \ne \text{chip}(b)} M_{ab},

with :math:`M` the messages per frame from core ``a`` to core ``b``
(:func:`~compiler.passes.place_traffic.core_messages`: spikes per neuron × distinct
destination cores, so the projections with the most spike traffic weigh most).  Two
starting partitions — the placer's order (``core // C``) and a greedy growth (each chip
seeded with the busiest free core, then grown by the free core exchanging most messages
with it) — the one with the smaller cut is refined by pairwise swaps of cores between
chips while a swap lowers the cut (Kernighan–Lin style, sizes kept).  The result is never
worse than the placer's order.  Deterministic.

Examples
--------
>>> import scipy.sparse as sp
>>> m = sp.csr_matrix(np.array([[0, 0, 5, 0], [0, 0, 0, 5], [5, 0, 0, 0], [0, 5, 0, 0.]]))
>>> chip_assignment(m, 2).tolist()   # cores 0 and 2 talk, as do 1 and 3
[0, 2, 1, 3]
>>> chip_cut(m, np.array([0, 2, 1, 3]) // 2)
0.0
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["chip_assignment", "chip_cut", "chip_matrix"]

_MAX_PASSES = 8


def chip_cut(messages, chip: np.ndarray) -> float:
    """Messages per frame between cores on different chips (``chip[a]`` of each core)."""
    m = sp.coo_matrix(messages)
    return float(m.data[chip[m.row] != chip[m.col]].sum())


def chip_matrix(messages, chip: np.ndarray, n_chips: int) -> np.ndarray:
    """``(n_chips × n_chips)`` messages per frame from chip to chip (diagonal: on-chip).

    Examples
    --------
    >>> chip_matrix(sp.csr_matrix(np.array([[0, 2.0], [1, 0]])), np.array([0, 1]), 2).tolist()
    [[0.0, 2.0], [1.0, 0.0]]
    """
    m = sp.coo_matrix(messages)
    out = np.zeros((n_chips, n_chips))
    np.add.at(out, (chip[m.row], chip[m.col]), m.data)
    return out


def _grown(w: sp.csr_matrix, sizes: list[int]) -> np.ndarray:
    n = w.shape[0]
    chip = np.full(n, -1, np.int64)
    busy = np.asarray(w.sum(axis=1)).ravel()
    for c, size in enumerate(sizes):
        link = np.zeros(n)  # messages between each core and chip c so far
        for _ in range(size):
            free = chip < 0
            score = np.where(free, link, -np.inf)
            if not link[free].any():  # seed (or nothing links to the chip): the busiest free core
                score = np.where(free, busy, -np.inf)
            a = int(np.argmax(score))
            chip[a] = c
            link += w.getrow(a).toarray().ravel()
    return chip


def _refined(w: sp.csr_matrix, chip: np.ndarray, n_chips: int) -> np.ndarray:
    chip = chip.copy()
    n = w.shape[0]
    conn = np.asarray(w @ sp.csr_matrix((np.ones(n), (np.arange(n), chip)),
                                        shape=(n, n_chips)).toarray())
    tol = 1e-9 * max(float(w.data.sum()), 1.0)
    active = np.flatnonzero(np.diff(w.indptr))  # cores with any traffic
    for _ in range(_MAX_PASSES):
        swapped = False
        for a in active:
            ca = chip[a]
            row = w.getrow(a).toarray().ravel()
            gain = (conn[a, chip] - conn[a, ca]) + (conn[np.arange(n), ca]
                                                    - conn[np.arange(n), chip]) - 2 * row
            gain[chip == ca] = -np.inf
            b = int(np.argmax(gain))
            if gain[b] <= tol:
                continue
            cb = chip[b]
            rb = w.getrow(b).toarray().ravel()
            conn[:, ca] += rb - row
            conn[:, cb] += row - rb
            chip[a], chip[b] = cb, ca
            swapped = True
        if not swapped:
            break
    return chip


def chip_assignment(messages, cores_per_chip: int) -> np.ndarray:
    """New core numbers such that ``new // cores_per_chip`` is a traffic-minimising chip.

    Parameters
    ----------
    messages : sparse or dense (n, n)
        Messages per frame from core to core (the placer's numbering).
    cores_per_chip : int
        Cores of one chip.

    Returns
    -------
    ndarray of int, shape (n,)
        A permutation of ``0 … n-1``: the new number of each core.  Chip ``c`` holds
        ``c·C … c·C + C - 1`` (the last chip the rest), each chip's cores in their old order.
    """
    w = sp.csr_matrix(messages, dtype=np.float64)
    n = w.shape[0]
    w = (w + w.T).tocsr()
    w.setdiag(0)
    w.eliminate_zeros()
    n_chips = -(-n // cores_per_chip)
    start = np.arange(n) // cores_per_chip
    if n_chips <= 1 or w.nnz == 0:
        return np.arange(n)
    sizes = np.bincount(start, minlength=n_chips).tolist()
    grown = _grown(w, sizes)
    best = start if chip_cut(w, start) <= chip_cut(w, grown) else grown
    chip = _refined(w, best, n_chips)
    if chip_cut(w, chip) >= chip_cut(w, start):  # never worse than the placer's order
        chip = start
    order = np.lexsort((np.arange(n), chip))  # by chip, then by old number
    new = np.empty(n, np.int64)
    new[order] = np.arange(n)
    return new
