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
>>> q_levels, q = quantize(np.array([[1.0, -0.5], [0.26, 0.0]]), bits=3)
>>> q_levels.tolist(), q
([[3.0, -2.0], [1.0, 0.0]], 0.3333333333333333)
"""

from __future__ import annotations

import numpy as np

from ir.errors import CompileError

__all__ = ["EXACT_WEIGHT_BITS", "quantize", "weight_bits_of"]

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


def quantize(m: np.ndarray, bits: int) -> tuple[np.ndarray, float]:
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
    >>> levels, q = quantize(np.array([0.5, -1.0]), bits=8)
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
