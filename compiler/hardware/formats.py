r"""A chip's number formats: weight mantissa and exponent, threshold and bias encodings.

Every value a neuron core stores is an integer in *state units* (the membrane's least
significant bit).  A hardware profile says how each kind of value is encoded:

* **weights** — a signed mantissa of ``weight_bits`` (``|m| ≤ 2^{b_w−1} − 1``) times
  ``2^e`` with one exponent ``e ∈ [0, weight_exponent_max]`` per projection (a synapse
  group / synapse format on Loihi);
* **thresholds** — an unsigned mantissa of ``threshold_mantissa_bits`` times
  ``2^{threshold_shift}``, at most ``2^{threshold_bits−1} − 1``;
* **biases** — a signed mantissa of ``bias_mantissa_bits`` times ``2^e``,
  ``e ∈ [0, bias_exponent_max]``.

:func:`weight_terms` writes a real weight array as a sum of such terms: one term when it
fits (rounded to its exponent), several — a *split* synapse — when exact whole numbers
need more mantissa bits than one exponent gives (an OS-CFAR's cell-under-test weight
``k = 255`` on 8 bits: ``127·2 + 1``).

Examples
--------
>>> [(e, t.tolist()) for e, t in weight_terms(np.array([198.0, -2.0]), 127, 13, exact=True)]
[(1, [198.0, -2.0])]
>>> [(e, t.tolist()) for e, t in weight_terms(np.array([198.0, -1.0]), 127, 13, exact=True)]
[(1, [198.0, -0.0]), (0, [0.0, -1.0])]
>>> [(e, t.tolist()) for e, t in weight_terms(np.array([255.0]), 127, 13, exact=True)]
[(1, [254.0]), (0, [1.0])]
>>> bias_value(12345.0, mantissa_bits=13, exponent_max=7)
12344.0
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_WEIGHT_TERMS", "exponent_for", "weight_terms", "bias_value"]

#: Most terms one weight is split into (8-bit mantissas: exact up to ~2^28 in 4 terms).
MAX_WEIGHT_TERMS = 4


def exponent_for(w: np.ndarray, w_max: int, e_max: int, rounding=np.rint) -> int:
    """The smallest exponent ``e ≤ e_max`` with every ``|rounding(w / 2^e)| ≤ w_max``
    (else ``e_max``).

    Examples
    --------
    >>> exponent_for(np.array([100.0]), 127, 7), exponent_for(np.array([300.0]), 127, 7)
    (0, 2)
    """
    peak = float(np.abs(w).max(initial=0.0))
    if peak <= w_max:
        return 0
    e = max(0, math.ceil(math.log2(peak / w_max)) - 1)
    while e < e_max and np.abs(rounding(np.ldexp(w, -e))).max() > w_max:
        e += 1
    return min(e, e_max)


def weight_terms(w: np.ndarray, w_max: int, e_max: int, *,
                 exact: bool) -> list[tuple[int, np.ndarray]]:
    """``w`` as terms ``(e, m·2^e)`` of one exponent each, mantissas within ``±w_max``.

    Parameters
    ----------
    w : ndarray
        Weights in state units.
    w_max : int
        Largest mantissa magnitude, ``2**(weight_bits - 1) - 1``.
    e_max : int
        Largest exponent.
    exact : bool
        ``w`` holds whole numbers that must be kept exactly: the rounding residual of
        each term is written as further terms (at most :data:`MAX_WEIGHT_TERMS`).
        Otherwise one term, rounded to the nearest representable value.

    Returns
    -------
    list of (int, ndarray)
        The first term has the shape of ``w``; a further term is non-zero only where the
        weight needed it (stored zeros are no synapses).
    """
    terms, rest = [], np.asarray(w, np.float64)
    while True:
        split = exact and len(terms) < MAX_WEIGHT_TERMS - 1  # truncate: a whole residual
        rounding = np.trunc if split else np.rint
        e = exponent_for(rest, w_max, e_max, rounding)
        m = np.clip(rounding(np.ldexp(rest, -e)), -w_max, w_max)
        term = np.ldexp(m, e)
        terms.append((e, term))
        rest = rest - term
        if not exact or not rest.any() or len(terms) == MAX_WEIGHT_TERMS:
            return terms


def bias_value(b: float, *, mantissa_bits: int | None, exponent_max: int) -> float:
    """The nearest bias ``m·2^e`` (``|m| < 2^{mantissa_bits−1}``, ``0 ≤ e ≤ exponent_max``).

    Examples
    --------
    >>> bias_value(3.0, mantissa_bits=13, exponent_max=7), bias_value(-8191.0, mantissa_bits=13,
    ...                                                                exponent_max=0)
    (3.0, -4095.0)
    """
    if mantissa_bits is None or b == 0:
        return float(b)
    m_max = (1 << (mantissa_bits - 1)) - 1
    e = 0
    while e < exponent_max and abs(b) / 2 ** e > m_max:
        e += 1
    return float(np.clip(np.rint(b / 2 ** e), -m_max, m_max) * 2 ** e)
