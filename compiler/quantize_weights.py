r"""Symmetric weight quantization to a target's weight bits (the ``weight_bits`` option).

A real matrix ``M`` becomes integer levels ``Q`` and one scale ``q``:

.. math::

    L = 2^{b-1} - 1, \qquad q = \max|M| / L, \qquad Q = \mathrm{rint}(M / q)
    \in \{-L, \dots, L\}, \qquad |M - qQ| \le q/2

The network stores the integers ``Q`` (exact in float64 and in fixed point);
``q`` moves into the thresholds and decoders.  Without a target width the
spiking motifs use :data:`EXACT_WEIGHT_BITS` = 24 bits, a relative error below
``6·10⁻⁸`` of the largest weight — far under any time code's resolution — that
keeps every membrane sum an exact integer, so the closed-form and step
engines agree bit for bit.

Examples
--------
>>> import numpy as np
>>> q_levels, q = quantize_matrix(np.array([[1.0, -0.5], [0.26, 0.0]]), bits=3)
>>> q_levels.tolist(), q
([[3.0, -2.0], [1.0, 0.0]], 0.3333333333333333)
"""

from __future__ import annotations

import numpy as np

from ir.errors import CompileError

__all__ = ["EXACT_WEIGHT_BITS", "quantize_matrix", "rint_feedback", "rint_keep_sums",
           "weight_bits_of"]

#: Bits used when no target width is given (see the module docstring).
EXACT_WEIGHT_BITS = 24


def weight_bits_of(option: object, *, node: str = "") -> int:
    """The weight width to use: the ``weight_bits`` option, or :data:`EXACT_WEIGHT_BITS`.

    Raises
    ------
    CompileError
        If the option is not an integer in ``2 … 32``.

    Examples
    --------
    >>> weight_bits_of(None), weight_bits_of(8)
    (24, 8)
    """
    if option is None:
        return EXACT_WEIGHT_BITS
    whole = isinstance(option, int | np.integer) and not isinstance(option, bool)
    if not whole or not 2 <= option <= 32:
        raise CompileError(f"node {node!r}: weight_bits={option!r} must be an integer in 2..32 "
                           "(sign included); use None for exact weights", node=node or None)
    return int(option)


def quantize_matrix(m: np.ndarray, bits: int) -> tuple[np.ndarray, float]:
    """Integer levels ``Q`` (as float64) and the scale ``q`` with ``M ≈ q·Q``.

    Parameters
    ----------
    m : ndarray
        Real weights.
    bits : int
        Width including the sign (``2 … 32``).

    Returns
    -------
    levels : ndarray of float64
        Integers in ``[-(2**(bits-1) - 1), 2**(bits-1) - 1]``.
    scale : float
        ``q``; 1.0 for an all-zero matrix.

    Raises
    ------
    CompileError
        For a bad ``bits`` or non-finite weights.

    Examples
    --------
    >>> levels, q = quantize_matrix(np.array([0.5, -1.0]), bits=8)
    >>> levels.tolist(), q * 127
    ([64.0, -127.0], 1.0)
    """
    bits = weight_bits_of(bits)
    m = np.asarray(m, dtype=np.float64)
    if not np.all(np.isfinite(m)):
        raise CompileError("weights to quantize contain NaN or Inf")
    peak = float(np.max(np.abs(m))) if m.size else 0.0
    if peak == 0.0:
        return np.zeros_like(m), 1.0
    scale = peak / (2 ** (bits - 1) - 1)
    return np.rint(m / scale), scale


def rint_keep_sums(x: np.ndarray, axis: int = 0) -> np.ndarray:
    r"""Round to whole numbers so that every sum along ``axis`` is the rounded true sum.

    Each entry goes to its floor or its ceiling (error below one level); per line along
    ``axis`` the ``rint(Σ x) − Σ floor(x)`` entries with the largest fractional parts
    round up (the largest-remainder method).  For a DFT or window matrix this keeps its
    response to a constant input — the static Tx→Rx leakage, ADC offset and static
    clutter over samples or chirps — as exact as the sum allows, where independent
    rounding leaks that strong return into every other bin at ``q/√12·√N``.

    Examples
    --------
    >>> x = np.array([[0.4, 0.4], [0.4, -0.4], [0.4, 0.0]])
    >>> np.rint(x).sum(axis=0).tolist(), rint_keep_sums(x).sum(axis=0).tolist()
    ([0.0, 0.0], [1.0, 0.0])
    >>> float(np.abs(rint_keep_sums(x) - x).max()) < 1
    True
    """
    x = np.asarray(x, dtype=np.float64)
    lo = np.floor(x)
    frac = x - lo
    deficit = np.rint(x.sum(axis=axis, keepdims=True)) - lo.sum(axis=axis, keepdims=True)
    order = np.argsort(-frac, axis=axis, kind="stable")
    rank = np.empty_like(order)
    shape = [1] * x.ndim
    shape[axis] = x.shape[axis]
    np.put_along_axis(rank, order, np.arange(x.shape[axis]).reshape(shape), axis=axis)
    return lo + (rank < deficit)


def rint_feedback(x: np.ndarray, h: np.ndarray, w_max: float, *, damp: float = 0.01,
                  block: int = 128) -> np.ndarray:
    r"""Round the rows of ``x`` one by one, feeding each row's error into the rows still to
    round so the output error on the calibration inputs is small (GPTQ's rule).

    With ``H = E[v vᵀ]`` the second moment of the layer's inputs (rows of ``x`` are inputs,
    columns outputs), the output error of levels ``Q`` is ``tr((x − Q)ᵀ H (x − Q))``.
    Row ``i`` is rounded, and its error ``e_i = (x_i − Q_i)/U_{ii}`` is removed from the
    rows after it, ``x_{j>i} −= U_{ij} e_i``, with ``U`` the upper Cholesky factor of
    ``(H + λ I)^{-1}`` (``λ`` = ``damp`` × the mean input power).  Strong inputs that
    repeat in the calibration data — the Tx→Rx leakage and static clutter of a radar —
    dominate ``H``, so the 8-bit rounding error stays out of the bins their spectrum
    would otherwise leak into.  Levels are clipped to ``±w_max``.

    Parameters
    ----------
    x : ndarray, shape (n_in, n_out)
        Weights in levels (already divided by the scale).
    h : ndarray, shape (n_in, n_in)
        Second moment of the inputs (any positive scale).
    w_max : float
        Largest level magnitude.
    damp, block : float, int
        Relative damping of ``H``; rows per lazily updated block.

    Returns
    -------
    ndarray
        Whole-number levels of ``x``'s shape.

    Examples
    --------
    Inputs that always arrive together (``v = (1, 1)``): the two roundings cancel.

    >>> x = np.array([[0.4], [0.4]])
    >>> h = np.ones((2, 2))
    >>> np.rint(x).ravel().tolist(), rint_feedback(x, h, 127).ravel().tolist()
    ([0.0, 0.0], [0.0, 1.0])
    """
    x = np.array(x, dtype=np.float64)
    n = x.shape[0]
    h = np.array(h, dtype=np.float64)
    diag = np.diag(h).copy()
    dead = diag <= 0
    h[dead, dead] = 1.0
    h[np.diag_indices(n)] += damp * max(float(diag[~dead].mean()) if (~dead).any() else 1.0,
                                        1e-300)
    try:
        lower = np.linalg.cholesky(h)
        hinv = np.linalg.solve(lower.T, np.linalg.solve(lower, np.eye(n)))
        u = np.linalg.cholesky(hinv).T
    except np.linalg.LinAlgError:  # not positive definite: plain rounding
        return np.clip(np.rint(x), -w_max, w_max)
    q = np.empty_like(x)
    for b0 in range(0, n, block):
        b1 = min(n, b0 + block)
        xb, err = x[b0:b1], np.empty((b1 - b0, x.shape[1]))
        for i in range(b1 - b0):
            qi = np.clip(np.rint(xb[i]), -w_max, w_max)
            q[b0 + i] = qi
            err[i] = (xb[i] - qi) / u[b0 + i, b0 + i]
            xb[i + 1:] -= np.outer(u[b0 + i, b0 + i + 1:b1], err[i])
        x[b1:] -= u[b0:b1, b1:].T @ err
    return q
