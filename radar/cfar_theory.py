"""False-alarm probability <-> threshold factor for CA- and OS-CFAR.

Model: square-law detector, the CUT and the ``N`` training cells i.i.d.
exponential (noise only), decision ``x_CUT > alpha * noise`` (radar.cfar). Then

* CA (noise = mean of N cells): ``Pfa = (1 + alpha/N)^(-N)``, so
  ``alpha = N (Pfa^(-1/N) - 1)``.
* OS (noise = k-th **largest** = m-th smallest, ``m = N - k + 1``):
  ``Pfa = prod_{i=0}^{m-1} (N - i) / (N - i + alpha)``, inverted numerically.

Both follow from ``Pfa = E[exp(-alpha * noise)]`` for a unit-mean exponential CUT.
Papers quoting the OS rank as "k-th smallest" ``k_s`` mean our ``k = N - k_s + 1``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ir.errors import RadarConfigError

__all__ = ["ca_pfa", "ca_alpha", "os_pfa", "os_alpha"]


def _n(n: object) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise RadarConfigError(f"number of training cells n={n!r} must be an integer >= 1")
    return int(n)


def _k(k: object, n: int) -> int:
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or not 1 <= k <= n:
        raise RadarConfigError(
            f"OS rank k={k!r} must be an integer in 1..{n} (k-th largest of n={n} cells); "
            "for a 'k-th smallest' k_s use k = n - k_s + 1"
        )
    return int(k)


def _alpha(alpha: object) -> float:
    if isinstance(alpha, bool) or not isinstance(alpha, int | float | np.integer | np.floating):
        raise RadarConfigError(f"alpha={alpha!r} must be a real number > 0")
    if not (math.isfinite(alpha) and alpha > 0):
        raise RadarConfigError(f"alpha={alpha!r} must be finite and > 0")
    return float(alpha)


def _pfa(pfa: object) -> float:
    if isinstance(pfa, bool) or not isinstance(pfa, int | float | np.integer | np.floating):
        raise RadarConfigError(f"pfa={pfa!r} must be a real number in (0, 1)")
    if not 0.0 < pfa < 1.0:
        raise RadarConfigError(f"pfa={pfa!r} is outside the open interval (0, 1), e.g. 1e-3")
    return float(pfa)


def ca_pfa(alpha: float, n: int) -> float:
    """False-alarm probability of CA-CFAR with ``n`` training cells.

    Parameters
    ----------
    alpha : float
        Threshold factor, > 0.
    n : int
        Training cells, >= 1.

    Returns
    -------
    float
        ``(1 + alpha/n)^(-n)``.

    Raises
    ------
    RadarConfigError
        For ``alpha <= 0`` or ``n < 1``.

    Examples
    --------
    >>> ca_pfa(1.0, 1), round(ca_pfa(8.6388, 16), 6)
    (0.5, 0.001)
    """
    a, n = _alpha(alpha), _n(n)
    return math.exp(-n * math.log1p(a / n))


def ca_alpha(pfa: float, n: int) -> float:
    """CA-CFAR threshold factor for a false-alarm probability.

    Parameters
    ----------
    pfa : float
        Target false-alarm probability in (0, 1).
    n : int
        Training cells, >= 1.

    Returns
    -------
    float
        ``n (pfa^(-1/n) - 1)``.

    Raises
    ------
    RadarConfigError
        For ``pfa`` outside (0, 1) or ``n < 1``.

    Examples
    --------
    >>> round(ca_alpha(1e-3, 16), 4)
    8.6388
    """
    p, n = _pfa(pfa), _n(n)
    return n * math.expm1(-math.log(p) / n)


def _os_log_pfa(alpha: float, n: int, m: int) -> float:
    """``log Pfa`` of OS-CFAR using the m-th smallest of n cells."""
    i = np.arange(m, dtype=np.float64)
    return float(np.sum(np.log(n - i) - np.log(n - i + alpha)))


def os_pfa(alpha: float, n: int, k: int) -> float:
    """False-alarm probability of OS-CFAR on the k-th largest of ``n`` training cells.

    Parameters
    ----------
    alpha : float
        Threshold factor, > 0.
    n : int
        Training cells, >= 1.
    k : int
        Rank, k-th **largest**, ``1..n``.

    Returns
    -------
    float
        ``prod_{i=0}^{m-1} (n-i)/(n-i+alpha)`` with ``m = n - k + 1``.

    Raises
    ------
    RadarConfigError
        For ``alpha <= 0``, ``n < 1`` or ``k`` outside ``1..n``.

    Examples
    --------
    With one cell OS equals CA; k=5 of 16 is the 12th smallest:

    >>> os_pfa(1.0, 1, 1), round(os_pfa(7.42141, 16, 5), 6)
    (0.5, 0.001)
    """
    a, n = _alpha(alpha), _n(n)
    m = n - _k(k, n) + 1
    return math.exp(_os_log_pfa(a, n, m))


def os_alpha(pfa: float, n: int, k: int) -> float:
    """OS-CFAR threshold factor for a false-alarm probability (k-th largest of ``n``).

    Parameters
    ----------
    pfa : float
        Target false-alarm probability in (0, 1).
    n : int
        Training cells, >= 1.
    k : int
        Rank, k-th **largest**, ``1..n``.

    Returns
    -------
    float
        The ``alpha > 0`` with ``os_pfa(alpha, n, k) == pfa`` (relative accuracy ~1e-13).

    Raises
    ------
    RadarConfigError
        For ``pfa`` outside (0, 1), ``n < 1`` or ``k`` outside ``1..n``.

    Examples
    --------
    >>> round(os_alpha(1e-3, 16, 5), 4)
    7.4214

    Notes
    -----
    ``log Pfa(alpha)`` falls strictly from 0 at ``alpha = 0`` to ``-inf``; the root of
    ``log Pfa(alpha) - log pfa`` is bracketed by doubling an upper bound and found by
    ``scipy.optimize.brentq``.
    """
    p, n = _pfa(pfa), _n(n)
    m = n - _k(k, n) + 1
    target = math.log(p)

    def excess(alpha: float) -> float:
        return _os_log_pfa(alpha, n, m) - target

    upper = 1.0
    while excess(upper) > 0.0:  # at most ~1000 doublings before float overflow
        upper *= 2.0
        if not math.isfinite(upper):
            raise RadarConfigError(
                f"pfa={p!r} with n={n}, k={k} needs an alpha beyond the float range; "
                "use a larger pfa"
            )
    return float(brentq(excess, 0.0, upper, xtol=1e-300, rtol=4 * np.finfo(float).eps))
