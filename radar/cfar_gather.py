"""CFAR noise by gathering every cell's training values: OS thresholds and the slow reference.

This is the original implementation of :func:`radar.cfar.noise_estimate` (docs/cfar.md):
pad each CFAR axis by ``g_i + t_i`` (circularly, or with NaN for clip), take a
``sliding_window_view`` and gather the masked training cells block by block (about
``2**21`` values per block), so memory stays bounded for large maps.  OS uses
``np.partition`` for cells with the full training set and a sort for the clipped border
cells; CA sums each cell's training values in stencil order with numpy's reduction.

:mod:`radar.cfar` still uses it for OS thresholds (``noise_estimate`` / ``cfar_threshold``
with ``kind="os"``); everything else there runs on :mod:`radar.cfar_fast`, whose results
the tests and ``benchmarks/cfar_speed.py`` compare with this module bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from radar.cfar_window import _mask, effective_k

__all__ = ["gather_noise"]

#: Training-cell values gathered per block (float64): bounds peak memory to a few x 16 MB.
_BLOCK_ELEMENTS = 1 << 21


def _ca_rows(vals: np.ndarray, n_avail: np.ndarray, k: int | None, n_total: int) -> np.ndarray:
    """Mean of the non-NaN entries of each row."""
    if np.all(n_avail == n_total):
        return vals.sum(axis=-1) / n_total
    return np.where(np.isnan(vals), 0.0, vals).sum(axis=-1) / n_avail


def _os_rows(vals: np.ndarray, n_avail: np.ndarray, k: int, n_total: int) -> np.ndarray:
    """k_eff-th largest non-NaN entry of each row (NaN sorts last in numpy)."""
    full = n_avail == n_total
    if full.all():
        return np.partition(vals, n_total - k, axis=-1)[:, n_total - k]
    out = np.empty(vals.shape[0])
    if full.any():
        out[full] = np.partition(vals[full], n_total - k, axis=-1)[:, n_total - k]
    part = ~full
    n_part = n_avail[part]
    pos = n_part - effective_k(k, n_part, n_total)
    out[part] = np.take_along_axis(np.sort(vals[part], axis=-1), pos[:, None], axis=-1)[:, 0]
    return out


#: Noise estimators by CFAR kind: (training values with NaN = missing, n_avail, k, N) -> noise.
_ESTIMATORS: Mapping[str, Callable[..., np.ndarray]] = {"ca": _ca_rows, "os": _os_rows}


def _blocks(n_batch: int, n_rows: int, rows_per_block: int) -> Iterator[tuple[slice, slice]]:
    """(batch slice, first-map-axis slice) pairs covering the input in bounded blocks."""
    if rows_per_block >= n_rows:
        step = rows_per_block // n_rows
        for b0 in range(0, n_batch, step):
            yield slice(b0, b0 + step), slice(None)
    else:
        for b in range(n_batch):
            for r0 in range(0, n_rows, rows_per_block):
                yield slice(b, b + 1), slice(r0, r0 + rows_per_block)


def _rows_per_block(map_shape: tuple[int, ...], n_total: int) -> int:
    """First-map-axis rows gathered per block (``_BLOCK_ELEMENTS`` values, at least one row)."""
    cells_per_row = int(np.prod(map_shape[1:], dtype=np.int64))
    return max(1, _BLOCK_ELEMENTS // (cells_per_row * n_total))


def _pad(
    arr: np.ndarray, guard: tuple[int, ...], train: tuple[int, ...], edge: tuple[str, ...]
) -> np.ndarray:
    """Pad the last ``len(guard)`` axes by ``g+t`` per side: circularly or with NaN."""
    lead = [(0, 0)] * (arr.ndim - len(guard))
    reach = [g + t for g, t in zip(guard, train, strict=True)]
    for mode, np_mode, fill in (
        ("wrap", "wrap", {}),
        ("clip", "constant", {"constant_values": np.nan}),
    ):
        widths = [(r, r) if m == mode else (0, 0) for r, m in zip(reach, edge, strict=True)]
        arr = np.pad(arr, lead + widths, mode=np_mode, **fill)
    return arr


def gather_noise(
    arr: np.ndarray,
    *,
    kind: str,
    guard: tuple[int, ...],
    train: tuple[int, ...],
    edge: tuple[str, ...],
    k: int | None,
    counts: np.ndarray,
) -> np.ndarray:
    """CFAR noise of every cell from its gathered training values (validated arguments).

    Parameters
    ----------
    arr : ndarray of float64
        Finite map(s); CFAR runs over the last ``len(guard)`` axes.
    kind : {"ca", "os"}
        Cell average or ordered statistic (k-th largest).
    guard, train, edge : tuple
        One width / edge mode per CFAR axis (as :func:`radar.cfar_window._stencil` returns).
    k : int or None
        OS rank, ``1..N``; ``None`` for CA.
    counts : ndarray of int64
        ``training_counts`` of the map shape, every entry ``>= 1``.

    Returns
    -------
    ndarray of float64, same shape as ``arr``

    Examples
    --------
    >>> from radar.cfar_window import training_counts
    >>> x = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    >>> n = training_counts((6,), guard=0, train=2)
    >>> gather_noise(x, kind="os", guard=(0,), train=(2,), edge=("clip",), k=1,
    ...              counts=n).tolist()
    [3.0, 4.0, 5.0, 6.0, 6.0, 5.0]
    """
    d = len(guard)
    mask = _mask(guard, train)
    n_total = int(mask.sum())
    map_shape = arr.shape[arr.ndim - d :]
    padded = _pad(arr, guard, train, edge)
    n_batch = int(np.prod(arr.shape[: arr.ndim - d], dtype=np.int64))
    padded = padded.reshape((n_batch, *padded.shape[arr.ndim - d :]))
    view = sliding_window_view(padded, mask.shape, axis=tuple(range(1, d + 1)))
    out = np.empty((n_batch, *map_shape))
    estimator = _ESTIMATORS[kind]
    for bs, rs in _blocks(n_batch, map_shape[0], _rows_per_block(map_shape, n_total)):
        vals = view[bs, rs][..., mask]
        block_shape = vals.shape[:-1]
        n_avail = np.broadcast_to(counts[rs], block_shape).reshape(-1)
        est = estimator(vals.reshape(-1, n_total), n_avail, k, n_total)
        out[bs, rs] = est.reshape(block_shape)
    return out.reshape(arr.shape)
