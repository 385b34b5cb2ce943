r"""Fast conventional CFAR kernels, bit-equal to the gathered implementation (radar.cfar_gather).

:mod:`radar.cfar` runs CA noise/thresholds/decisions and OS decisions here; why each
kernel returns exactly what :func:`radar.cfar_gather.gather_noise` (and a threshold
``alpha * noise`` compared with ``x``) returns:

* **CA, integer-valued maps** whose padded ``sum |x| <= 2**(51 - d)``: summed-area tables
  (cumulative sums, 2**d corners per box). Every partial sum of either method is an integer
  below ``2**53``, so both are the exact sum, whatever the order; ``+ 0.0`` maps a ``-0.0``
  to ``0.0`` as the gather's ``0.0 + ...`` does.
* **CA, other maps**: the gather reduces an array whose training axis is the outer one in
  memory, so numpy adds each cell's values in stencil (raster) order, ``((0 + v_0) + v_1) +
  ...``, missing (clipped) cells as ``0.0``. Here the same additions run on whole maps, one
  shifted view per training offset. A block of a single cell is contiguous and numpy sums it
  pairwise instead; :func:`_lone_rows` finds those cells and they are summed the same way.
* **OS decisions**: with ``T`` the ``k_eff``-th largest training value and ``A(v) =
  fl(alpha * v)`` non-decreasing in ``v``, ``x > A(T)`` holds iff fewer than ``k_eff``
  training values have ``A(v) >= x`` (the values failing ``x > A(v)`` are the largest ones).
  So one comparison per training offset and a count replace the order statistic.

The tests (tests/test_cfar_fast.py) check all three against the gather, bit for bit.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from radar.cfar_gather import _rows_per_block
from radar.cfar_window import _mask, effective_k

__all__ = ["window_sums", "ca_noise", "os_detect"]


def _pad(arr: np.ndarray, reach: list[int], edge: tuple[str, ...], fill: float) -> np.ndarray:
    """Pad the last ``len(reach)`` axes: circularly on wrap axes (first), then ``fill`` on clip."""
    lead = [(0, 0)] * (arr.ndim - len(reach))
    wrap = [(r, r) if m == "wrap" else (0, 0) for r, m in zip(reach, edge, strict=True)]
    clip = [(r, r) if m == "clip" else (0, 0) for r, m in zip(reach, edge, strict=True)]
    arr = np.pad(arr, lead + wrap, mode="wrap")
    return np.pad(arr, lead + clip, mode="constant", constant_values=fill)


def _shifted(padded: np.ndarray, mask: np.ndarray, map_shape: tuple[int, ...]) -> Iterator:
    """One map-shaped view of ``padded`` per training offset, in stencil (raster) order."""
    axes = tuple(range(padded.ndim - len(map_shape), padded.ndim))
    windows = sliding_window_view(padded, mask.shape, axis=axes)
    for off in np.argwhere(mask).tolist():
        yield windows[(Ellipsis, *off)]


def _box(table: np.ndarray, start: list[int], width: list[int], map_shape: tuple) -> np.ndarray:
    """Sum of the ``width`` box at ``start`` (padded coordinates), from a summed-area table."""
    d, total = len(start), np.zeros(table.shape[: table.ndim - len(start)] + map_shape)
    for corner in itertools.product((0, 1), repeat=d):
        idx = tuple(
            slice(s + c * w, s + c * w + n)
            for s, w, n, c in zip(start, width, map_shape, corner, strict=True)
        )
        view = table[(Ellipsis, *idx)]
        if (d - sum(corner)) % 2:
            total -= view
        else:
            total += view
    return total


def _sat_sums(padded: np.ndarray, guard: tuple, train: tuple, map_shape: tuple) -> np.ndarray:
    """Training sums by summed-area tables: window box minus guard box (exact for small ints)."""
    d = len(guard)
    table = padded
    for axis in range(padded.ndim - d, padded.ndim):
        table = np.cumsum(table, axis=axis)
    table = np.pad(table, [(0, 0)] * (padded.ndim - d) + [(1, 0)] * d)
    spans = [2 * (g + t) + 1 for g, t in zip(guard, train, strict=True)]
    window = _box(table, [0] * d, spans, map_shape)
    block = _box(table, list(train), [2 * g + 1 for g in guard], map_shape)
    return (window - block) + 0.0


def _lone_rows(map_shape: tuple[int, ...], n_total: int) -> list[int]:
    """First-axis rows the gather reduces as a block of one cell (numpy then sums pairwise)."""
    n_rows, per_block = map_shape[0], _rows_per_block(map_shape, n_total)
    if math.prod(map_shape[1:]) != 1 or per_block >= n_rows:
        return []
    if per_block == 1:
        return list(range(n_rows))
    return [n_rows - 1] if n_rows % per_block == 1 else []


def window_sums(
    arr: np.ndarray, *, guard: tuple[int, ...], train: tuple[int, ...], edge: tuple[str, ...]
) -> np.ndarray:
    """Sum of every cell's training values (clipped cells count 0), as the gather sums them.

    Parameters
    ----------
    arr : ndarray of float64
        Finite map(s); CFAR runs over the last ``len(guard)`` axes.
    guard, train, edge : tuple
        One width / edge mode per CFAR axis.

    Returns
    -------
    ndarray of float64, same shape as ``arr``

    Examples
    --------
    >>> window_sums(np.array([1.0, 2.0, 3.0, 4.0]), guard=(0,), train=(1,),
    ...             edge=("clip",)).tolist()
    [2.0, 4.0, 6.0, 3.0]
    >>> window_sums(np.array([0.5, 2.0, 3.0, 4.0]), guard=(0,), train=(1,),
    ...             edge=("wrap",)).tolist()
    [6.0, 3.5, 6.0, 3.5]
    """
    d = len(guard)
    map_shape = arr.shape[arr.ndim - d :]
    mask = _mask(guard, train)
    padded = _pad(arr, [g + t for g, t in zip(guard, train, strict=True)], edge, 0.0)
    if np.array_equal(np.rint(padded), padded) and np.abs(padded).sum() <= 2.0 ** (51 - d):
        return _sat_sums(padded, guard, train, map_shape)
    total = np.zeros(arr.shape)
    for view in _shifted(padded, mask, map_shape):
        total += view
    lone = _lone_rows(map_shape, int(mask.sum()))
    if lone:
        batch = padded.reshape((-1, *padded.shape[arr.ndim - d :]))
        flat = total.reshape((-1, *map_shape))
        for b, r in itertools.product(range(batch.shape[0]), lone):
            window = batch[b][(slice(r, r + mask.shape[0]), *(slice(0, w) for w in mask.shape[1:]))]
            flat[(b, r, *([0] * (d - 1)))] = window[mask].sum()
    return total


def ca_noise(
    arr: np.ndarray,
    *,
    guard: tuple[int, ...],
    train: tuple[int, ...],
    edge: tuple[str, ...],
    counts: np.ndarray,
) -> np.ndarray:
    """CA noise: :func:`window_sums` divided by the in-map training counts ``n_avail``.

    Parameters
    ----------
    arr : ndarray of float64
        Finite map(s).
    guard, train, edge : tuple
        One width / edge mode per CFAR axis.
    counts : ndarray of int64
        ``radar.cfar_window.training_counts`` of the map shape, every entry ``>= 1``.

    Returns
    -------
    ndarray of float64, same shape as ``arr``

    Examples
    --------
    >>> ca_noise(np.array([1.0, 2.0, 3.0, 4.0]), guard=(0,), train=(1,), edge=("clip",),
    ...          counts=np.array([1, 2, 2, 1])).tolist()
    [2.0, 2.0, 3.0, 3.0]
    """
    return window_sums(arr, guard=guard, train=train, edge=edge) / counts


def os_detect(
    arr: np.ndarray,
    *,
    guard: tuple[int, ...],
    train: tuple[int, ...],
    edge: tuple[str, ...],
    k: int,
    counts: np.ndarray,
    alpha: float,
) -> np.ndarray:
    """OS-CFAR decisions ``x > alpha * (k_eff-th largest training value)``, by counting.

    Parameters
    ----------
    arr : ndarray of float64
        Finite map(s).
    guard, train, edge : tuple
        One width / edge mode per CFAR axis.
    k : int
        Rank for the full training set, ``1..N`` (``k_eff`` on clipped cells).
    counts : ndarray of int64
        ``radar.cfar_window.training_counts`` of the map shape, every entry ``>= 1``.
    alpha : float
        Threshold factor ``> 0``.

    Returns
    -------
    ndarray of bool, same shape as ``arr``

    Examples
    --------
    >>> x = np.array([1.0, 1.0, 1.0, 8.0, 1.0, 1.0, 2.0])
    >>> np.flatnonzero(os_detect(x, guard=(1,), train=(2,), edge=("clip",), k=1,
    ...                          counts=np.array([2, 2, 3, 4, 3, 2, 2]), alpha=1.5)).tolist()
    [3]
    """
    d = len(guard)
    map_shape = arr.shape[arr.ndim - d :]
    mask = _mask(guard, train)
    n_total = int(mask.sum())
    scaled = _pad(alpha * arr, [g + t for g, t in zip(guard, train, strict=True)], edge, -np.inf)
    above = np.zeros(arr.shape, dtype=np.min_scalar_type(n_total))
    for view in _shifted(scaled, mask, map_shape):
        above += view >= arr
    return above < effective_k(k, counts, n_total)
