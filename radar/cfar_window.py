r"""CFAR training-window geometry: the stencil, its cell counts and the clipped OS rank.

One convention (docs/cfar.md), shared by :mod:`radar.cfar` and the spiking lowering:
``guard`` and ``train`` are widths **per side, per axis**; along axis ``i`` the window
spans ``2*(g_i + t_i) + 1`` cells and the guard block (including the cell under test)
``2*g_i + 1``; training cells = window minus guard block, so

.. math:: N = \prod_i (2(g_i + t_i) + 1) - \prod_i (2 g_i + 1).

Edges per axis: ``"wrap"`` (circular) keeps all ``N`` cells; ``"clip"`` drops cells outside
the map, leaving ``n_avail`` (:func:`training_counts`), and OS then uses the rank
``k_eff = clamp(ceil(k * n_avail / N), 1, n_avail)`` (:func:`effective_k`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ir.errors import RadarConfigError

__all__ = [
    "EDGE_MODES",
    "training_mask",
    "n_training",
    "training_counts",
    "effective_k",
]

EDGE_MODES = ("wrap", "clip")


def _widths(value: object, name: str) -> tuple[int, ...] | int:
    """A non-negative int or a tuple of them (validated, not yet broadcast)."""
    items = value if isinstance(value, Sequence | np.ndarray) else None
    for v in [value] if items is None else list(items):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 0:
            raise RadarConfigError(
                f"{name}={value!r}: widths must be non-negative integers (cells per side), "
                f"got {v!r}"
            )
    if items is None:
        return int(value)  # type: ignore[arg-type]
    if len(items) == 0:
        raise RadarConfigError(f"{name}={value!r} is empty; give one width per CFAR axis")
    return tuple(int(v) for v in items)


def _stencil(
    guard: object, train: object, edge: object = "clip", default_ndim: int = 1
) -> tuple[tuple[int, ...], tuple[int, ...], tuple[str, ...]]:
    """Validate and broadcast ``guard``, ``train``, ``edge`` to one entry per CFAR axis."""
    g, t = _widths(guard, "guard"), _widths(train, "train")
    if not isinstance(edge, str | Sequence):
        raise RadarConfigError(f"edge={edge!r} must be 'wrap', 'clip' or a list of them per axis")
    e = (edge,) if isinstance(edge, str) else tuple(edge)
    for mode in e:
        if mode not in EDGE_MODES:
            raise RadarConfigError(
                f"edge={edge!r}: {mode!r} is not an edge mode; use 'wrap' or 'clip' per axis"
            )
    lengths = {len(v) for v in (g, t) if isinstance(v, tuple)}
    lengths |= {len(e)} if not isinstance(edge, str) else set()
    if len(lengths) > 1:
        raise RadarConfigError(
            f"guard={guard!r}, train={train!r}, edge={edge!r} give different numbers of "
            f"axes {sorted(lengths)}; give one entry per CFAR axis (or a scalar for all)"
        )
    d = lengths.pop() if lengths else default_ndim
    g = g if isinstance(g, tuple) else (g,) * d
    t = t if isinstance(t, tuple) else (t,) * d
    e = e if len(e) == d else e * d
    if all(ti == 0 for ti in t):
        raise RadarConfigError(
            f"train={train!r} leaves no training cells; give at least one axis train >= 1"
        )
    return g, t, e


def _mask(guard: tuple[int, ...], train: tuple[int, ...]) -> np.ndarray:
    window = [2 * (g + t) + 1 for g, t in zip(guard, train, strict=True)]
    mask = np.ones(window, dtype=bool)
    mask[tuple(slice(t, t + 2 * g + 1) for g, t in zip(guard, train, strict=True))] = False
    return mask


def training_mask(guard: int | Sequence[int], train: int | Sequence[int]) -> np.ndarray:
    """The CFAR stencil: True on training cells, False on the guard block and CUT.

    Parameters
    ----------
    guard, train : int or sequence of int
        Widths per side, per axis. Two ints give a 1D stencil; for an n-D square
        stencil pass lists (``[2, 2]``).

    Returns
    -------
    ndarray of bool, shape ``(2*(g_i+t_i)+1, ...)``
        The CUT is the centre element.

    Raises
    ------
    RadarConfigError
        For negative/non-integer widths, mismatched lengths or no training cell.

    Examples
    --------
    >>> training_mask(1, 2).astype(int).tolist()
    [1, 1, 0, 0, 0, 1, 1]
    >>> training_mask([0, 1], [1, 0]).astype(int).tolist()
    [[1, 1, 1], [0, 0, 0], [1, 1, 1]]
    """
    g, t, _ = _stencil(guard, train)
    return _mask(g, t)


def n_training(guard: int | Sequence[int], train: int | Sequence[int]) -> int:
    """Number of training cells ``N = prod(2(g_i+t_i)+1) - prod(2 g_i+1)``.

    Parameters
    ----------
    guard, train : int or sequence of int
        As in :func:`training_mask`.

    Returns
    -------
    int

    Raises
    ------
    RadarConfigError
        As :func:`training_mask`.

    Examples
    --------
    >>> n_training([3, 3], [4, 4]), n_training([1, 1], [1, 1]), n_training(6, 15)
    (176, 16, 30)
    """
    return int(training_mask(guard, train).sum())


def _axis_counts(n: int, reach: int, mode: str) -> np.ndarray:
    """In-map cells at offsets -reach..reach from each position of an axis of length n."""
    if mode == "wrap":
        return np.full(n, 2 * reach + 1, dtype=np.int64)
    pos = np.arange(n, dtype=np.int64)
    return np.minimum(pos + reach, n - 1) - np.maximum(pos - reach, 0) + 1


def training_counts(
    shape: Sequence[int],
    *,
    guard: int | Sequence[int],
    train: int | Sequence[int],
    edge: str | Sequence[str] = "clip",
) -> np.ndarray:
    """Training cells inside the map, ``n_avail``, for every CUT of a map of ``shape``.

    Parameters
    ----------
    shape : sequence of int
        The map shape (the CFAR axes only).
    guard, train : int or sequence of int
        Widths per side, per axis (ints apply to every axis of ``shape``).
    edge : {"wrap", "clip"} or sequence of them
        Edge mode per axis.

    Returns
    -------
    ndarray of int64, shape ``shape``
        ``prod_i win_i(c_i) - prod_i grd_i(c_i)`` where ``win_i``/``grd_i`` count the
        in-map offsets of the window/guard block along axis ``i`` (all of them on a
        wrap axis).

    Raises
    ------
    RadarConfigError
        For bad widths/edges or a ``shape`` whose length differs from theirs.

    Examples
    --------
    >>> training_counts((6,), guard=1, train=2).tolist()
    [2, 2, 3, 3, 2, 2]
    >>> training_counts((6,), guard=1, train=2, edge="wrap").tolist()
    [4, 4, 4, 4, 4, 4]
    """
    shape = tuple(int(s) for s in shape)
    g, t, e = _stencil(guard, train, edge, default_ndim=len(shape))
    if len(g) != len(shape):
        raise RadarConfigError(
            f"shape {shape} has {len(shape)} axes but guard/train/edge describe {len(g)}"
        )
    window, block = np.ones((), np.int64), np.ones((), np.int64)
    for n, gi, ti, mode in zip(shape, g, t, e, strict=True):
        window = np.multiply.outer(window, _axis_counts(n, gi + ti, mode))
        block = np.multiply.outer(block, _axis_counts(n, gi, mode))
    return window - block


def effective_k(k: int, n_avail: object, n_total: int) -> np.ndarray:
    """OS rank used where only ``n_avail`` of ``n_total`` training cells exist.

    Parameters
    ----------
    k : int
        Rank (k-th largest, 1-indexed) for the full training set.
    n_avail : array_like of int
        Training cells inside the map, ``1..n_total``.
    n_total : int
        Full training set size ``N``.

    Returns
    -------
    ndarray of int64
        ``k_eff = clamp(ceil(k * n_avail / N), 1, n_avail)``; equals ``k`` where
        ``n_avail == N``.

    Examples
    --------
    >>> effective_k(12, [16, 8, 3, 1], 16).tolist()
    [12, 6, 3, 1]
    """
    n = np.asarray(n_avail, dtype=np.int64)
    return np.clip((k * n + n_total - 1) // n_total, 1, n)
