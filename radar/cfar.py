"""CA- and OS-CFAR in any number of dimensions, with one convention (docs/cfar.md).

Convention
----------
* ``guard`` and ``train`` are widths **per side, per axis**. Along axis ``i`` the
  window spans ``2*(g_i + t_i) + 1`` cells; the guard block (which includes the
  cell under test, CUT) spans ``2*g_i + 1``. Training cells = window minus guard
  block, e.g. guard ``[3, 3]``, train ``[4, 4]``: ``15*15 - 7*7 = 176`` cells.
* Noise estimate: CA = mean of the training cells; OS = the **k-th largest**
  training cell, ``k`` 1-indexed.
* Decision: detect when ``x_CUT > alpha * noise`` (strict).
* Edges per axis: ``"wrap"`` (circular, for Doppler) or ``"clip"`` (cells outside
  the map are dropped). With ``n_avail < N`` training cells left, CA averages the
  ``n_avail`` cells and OS takes the ``k_eff``-th largest of them, with
  ``k_eff = clamp(ceil(k * n_avail / N), 1, n_avail)``.
* CFAR runs over the last ``d`` axes, ``d`` = the length of ``guard``/``train``/``edge``
  when any is a sequence, else ``x.ndim``; leading axes are a batch.

The window geometry lives in :mod:`radar.cfar_window`, the kernels in :mod:`radar.cfar_fast`
(CA; OS decisions) and :mod:`radar.cfar_gather` (OS thresholds; the original code, the
bit-for-bit reference of ``_reference_noise_estimate`` / ``_reference_cfar``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ir.errors import RadarConfigError
from radar.cfar_fast import ca_noise, os_detect
from radar.cfar_gather import gather_noise
from radar.cfar_window import _mask, _stencil, training_counts

__all__ = [
    "CFAR_KINDS",
    "noise_estimate",
    "cfar_threshold",
    "cfar",
]

CFAR_KINDS = ("ca", "os")


@dataclass(frozen=True)
class _Window:
    """A validated CFAR problem: the float64 map(s) and one entry per CFAR axis."""

    arr: np.ndarray
    guard: tuple[int, ...]
    train: tuple[int, ...]
    edge: tuple[str, ...]
    k: int | None
    counts: np.ndarray

    @property
    def geometry(self) -> dict:
        """Keyword arguments of the kernels in radar.cfar_fast / radar.cfar_gather."""
        return {"guard": self.guard, "train": self.train, "edge": self.edge, "counts": self.counts}


def _check_input(x: object) -> np.ndarray:
    arr = np.asarray(x)
    if np.iscomplexobj(arr):
        raise RadarConfigError(
            "CFAR input x is complex; apply radar.dsp.magnitude (e.g. kind='square') first"
        )
    if arr.ndim == 0 or arr.size == 0:
        raise RadarConfigError(f"CFAR input x has shape {arr.shape}; it needs at least one cell")
    arr = arr.astype(np.float64, copy=False)
    bad = int(np.count_nonzero(~np.isfinite(arr)))
    if bad:
        raise RadarConfigError(
            f"CFAR input x has {bad} non-finite value(s) (NaN/inf) of {arr.size}; "
            "replace them (e.g. np.nan_to_num) before CFAR"
        )
    return arr


def _window(
    x: object,
    kind: str,
    guard: int | Sequence[int],
    train: int | Sequence[int],
    k: int | None,
    edge: str | Sequence[str],
) -> _Window:
    """Validate a CFAR call (errors as :func:`noise_estimate` documents them)."""
    if not isinstance(kind, str) or kind not in CFAR_KINDS:
        raise RadarConfigError(
            f"CFAR kind={kind!r} is not valid; use 'ca' (cell average) or 'os' (ordered statistic)"
        )
    arr = _check_input(x)
    g, t, e = _stencil(guard, train, edge, default_ndim=arr.ndim)
    d = len(g)
    if d > arr.ndim:
        raise RadarConfigError(
            f"guard/train/edge describe a {d}-D window but x has only {arr.ndim} dimension(s)"
        )
    mask = _mask(g, t)
    n_total = int(mask.sum())
    if kind == "ca" and k is not None:
        raise RadarConfigError(f"k={k!r} is only used by kind='os'; pass k=None for CA-CFAR")
    if kind == "os" and (
        isinstance(k, bool) or not isinstance(k, int | np.integer) or not 1 <= k <= n_total
    ):
        raise RadarConfigError(
            f"OS-CFAR k={k!r} must be an integer in 1..{n_total} (k-th largest of the "
            f"N={n_total} training cells for guard={list(g)}, train={list(t)}); "
            f"e.g. k={max(1, (3 * n_total) // 4)} (~3N/4)"
        )
    map_shape = arr.shape[arr.ndim - d :]
    for i, (n, gi, ti, mode) in enumerate(zip(map_shape, g, t, e, strict=True)):
        if mode == "wrap" and 2 * (gi + ti) + 1 > n:
            raise RadarConfigError(
                f"edge='wrap' on CFAR axis {i} (length {n}) needs the window "
                f"2*(guard+train)+1 = {2 * (gi + ti) + 1} <= {n}; reduce guard/train on "
                "that axis or use edge='clip'"
            )
    counts = training_counts(map_shape, guard=g, train=t, edge=e)
    if counts.min() < 1:
        cell = tuple(int(c) for c in np.unravel_index(np.argmin(counts), counts.shape))
        raise RadarConfigError(
            f"map shape {map_shape} is too small for guard={list(g)}, train={list(t)} with "
            f"edge={list(e)}: cell {cell} has no training cell inside the map; enlarge the "
            "map, reduce guard, or use edge='wrap'"
        )

    return _Window(arr, g, t, e, k, counts)


def noise_estimate(
    x: object,
    *,
    kind: str,
    guard: int | Sequence[int],
    train: int | Sequence[int],
    k: int | None = None,
    edge: str | Sequence[str] = "clip",
) -> np.ndarray:
    """CFAR noise estimate for every cell: mean (CA) or k-th largest (OS) training cell.

    Parameters
    ----------
    x : array_like of real
        Map(s); CFAR runs over the last ``d`` axes (see module notes), the rest is a batch.
    kind : {"ca", "os"}
        Cell averaging or ordered statistic.
    guard, train : int or sequence of int
        Widths per side, per axis.
    k : int, optional
        OS only: rank of the noise estimate, k-th largest, ``1 <= k <= N``.
    edge : {"wrap", "clip"} or sequence of them
        Edge mode per axis (see module notes for the clip renormalisation).

    Returns
    -------
    ndarray of float64, same shape as ``x``

    Raises
    ------
    RadarConfigError
        For complex or non-finite input, bad kind/widths/edges, ``k`` missing or outside
        ``1..N`` for OS (or given for CA), a wrap axis shorter than the window, more
        CFAR axes than ``x`` has, or a map so small that some cell has no training cell.

    Examples
    --------
    >>> x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    >>> noise_estimate(x, kind="ca", guard=1, train=1, edge="wrap").tolist()
    [4.0, 5.0, 3.0, 4.0, 2.0, 3.0]
    >>> noise_estimate(x, kind="os", guard=0, train=2, k=1).tolist()
    [3.0, 4.0, 5.0, 6.0, 6.0, 5.0]

    Notes
    -----
    CA sums each cell's training values in stencil (raster) order, ``((0 + v_0) + v_1)
    + ...``, on whole shifted maps (:func:`radar.cfar_fast.window_sums`), or by
    summed-area tables where that is provably exact (integer-valued maps); the result is
    bit-equal to the original gathered implementation. OS gathers each cell's training
    values (:func:`radar.cfar_gather.gather_noise`: ``np.partition``, a sort on clipped
    border cells); its estimate is exactly one of the inputs. :func:`cfar` does not
    need the OS estimate and counts instead (much faster, same decisions).
    """
    w = _window(x, kind, guard, train, k, edge)
    if kind == "ca":
        return ca_noise(w.arr, **w.geometry)
    return gather_noise(w.arr, kind=kind, k=k, **w.geometry)


def _alpha(alpha: object) -> float:
    if isinstance(alpha, bool) or not isinstance(alpha, int | float | np.integer | np.floating):
        raise RadarConfigError(f"CFAR alpha={alpha!r} must be a real number > 0")
    if not (np.isfinite(alpha) and alpha > 0):
        raise RadarConfigError(
            f"CFAR alpha={alpha!r} must be finite and > 0 (threshold = alpha * noise); a paper "
            "that scales the CUT by a<1 instead needs alpha = 1/a (docs/cfar.md)"
        )
    return float(alpha)


def cfar_threshold(
    x: object,
    *,
    kind: str,
    guard: int | Sequence[int],
    train: int | Sequence[int],
    alpha: float,
    k: int | None = None,
    edge: str | Sequence[str] = "clip",
) -> np.ndarray:
    """Adaptive CFAR threshold ``alpha * noise_estimate(x, ...)``.

    Parameters
    ----------
    x, kind, guard, train, k, edge
        As in :func:`noise_estimate`.
    alpha : float
        Threshold factor, ``> 0`` (see ``radar.cfar_theory`` for ``alpha`` from a Pfa).

    Returns
    -------
    ndarray of float64, same shape as ``x``

    Raises
    ------
    RadarConfigError
        For ``alpha <= 0`` or non-finite, and as :func:`noise_estimate`.

    Examples
    --------
    >>> cfar_threshold([1.0, 9.0, 1.0, 1.0], kind="ca", guard=0, train=1, alpha=2.0,
    ...                edge="wrap").tolist()
    [10.0, 2.0, 10.0, 2.0]
    """
    a = _alpha(alpha)
    return a * noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)


def cfar(
    x: object,
    *,
    kind: str = "ca",
    guard: int | Sequence[int],
    train: int | Sequence[int],
    alpha: float,
    k: int | None = None,
    edge: str | Sequence[str] = "clip",
) -> np.ndarray:
    """CFAR detections: ``x_CUT > alpha * noise`` (strict) for every cell.

    Parameters
    ----------
    x : array_like of real
        Map(s), ideally square-law (power) values for the Pfa theory to hold.
    kind : {"ca", "os"}
        Cell averaging (mean) or ordered statistic (k-th largest).
    guard, train : int or sequence of int
        Widths per side, per axis.
    alpha : float
        Threshold factor ``> 0``.
    k : int, optional
        OS only: k-th largest training cell, ``1..N``.
    edge : {"wrap", "clip"} or sequence of them
        Edge mode per axis.

    Returns
    -------
    ndarray of bool, same shape as ``x``

    Raises
    ------
    RadarConfigError
        As :func:`cfar_threshold`.

    Examples
    --------
    >>> x = [1.0, 1.0, 1.0, 8.0, 1.0, 1.0, 2.0]
    >>> np.flatnonzero(cfar(x, kind="ca", guard=1, train=2, alpha=4.0)).tolist()
    [3]
    >>> np.flatnonzero(cfar(x, kind="os", guard=1, train=2, k=1, alpha=1.5)).tolist()
    [3]

    Notes
    -----
    Equal values never detect: ``x = alpha * noise`` is not a detection. OS decisions
    are counted, not thresholded: ``x > alpha * T`` (``T`` the ``k_eff``-th largest)
    iff fewer than ``k_eff`` training cells have ``alpha * v >= x``
    (:func:`radar.cfar_fast.os_detect`), the same decisions as ``x > cfar_threshold(x)``.
    """
    a = _alpha(alpha)
    w = _window(x, kind, guard, train, k, edge)
    if kind == "os":
        return os_detect(w.arr, k=k, alpha=a, **w.geometry)
    return w.arr > a * ca_noise(w.arr, **w.geometry)


def _reference_noise_estimate(
    x: object,
    *,
    kind: str,
    guard: int | Sequence[int],
    train: int | Sequence[int],
    k: int | None = None,
    edge: str | Sequence[str] = "clip",
) -> np.ndarray:
    """:func:`noise_estimate` by the original gathered implementation (tests, benchmarks)."""
    w = _window(x, kind, guard, train, k, edge)
    return gather_noise(w.arr, kind=kind, k=k, **w.geometry)


def _reference_cfar(x: object, *, alpha: float, **params: object) -> np.ndarray:
    """:func:`cfar` by the original implementation: ``x > alpha * gathered noise``."""
    a = _alpha(alpha)
    return np.asarray(x, dtype=np.float64) > a * _reference_noise_estimate(x, **params)
