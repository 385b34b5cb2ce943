r"""Rotation coefficients of the resonators and the drift they cause.

Bin ``k`` rotates by ``a_k = ρ e^{iθ_k}`` per step.  In floating point ``a_k`` is exact
to rounding.  In fixed point (``F`` fraction bits, the Loihi decay format of 12 bits
by default, option ``resonator_coef_bits``) it is a Gaussian integer ``(C + iS)/2^F``,
and the error changes the response of bin ``k`` to its own frequency by the factor

.. math:: g_k = \frac{1}{N}\sum_{j=1}^{N} \big(\hat a_k e^{-iθ_k}\big)^j

(``N`` input steps; ``|1 − g_k|`` is the relative *drift* of the bin, magnitude and
phase: ``≈ N|â e^{−iθ} − 1|/2``).  :func:`fixed_coefficients` picks, among the lattice
points within 3 units of ``2^F ρ e^{iθ}``, the one with the least drift subject to
``|â| ≤ ρ`` — the state can never grow, however long the stream — at the chip's
:data:`CHIP_COEF_BITS` (or the bits the user gives), and the lowering reports a bound
above ``0.01`` (``compiler.lowering.resonator``).  The
rounding of each rotation adds at most half a unit per component and step, so after ``N``
steps a state differs from the exact product by at most ``N/√2`` units
(:func:`drift_report` states both bounds).

Examples
--------
>>> import numpy as np
>>> c, s = fixed_coefficients(np.array([0.0, np.pi / 2]), 1.0, 12, n_steps=1024)
>>> c.tolist(), s.tolist()
([4096.0, 0.0], [0.0, 4096.0])
"""

from __future__ import annotations

import numpy as np

__all__ = ["CHIP_COEF_BITS", "bin_angles", "float_coefficients", "fixed_coefficients",
           "bin_gains", "drift_report"]

#: Fraction bits of a chip's rotation coefficients: Lava's bit-accurate resonate-and-fire
#: model (``lava.proc.rf``, the fixed-point model also used for Loihi 2) holds ``sin_decay``
#: and ``cos_decay`` as 12-bit integers applied with a right shift of 12 — the only
#: published format; wider coefficients are the user's assumption (``resonator_coef_bits``).
CHIP_COEF_BITS = 12

_REACH = 3


def bin_angles(freqs: np.ndarray, n_fft: int) -> np.ndarray:
    """``θ_k = 2π f_k / N`` (rad per step) of bins at DFT frequencies ``f_k``."""
    return 2.0 * np.pi * np.asarray(freqs, np.float64) / n_fft


def float_coefficients(theta: np.ndarray, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """``(ρ cos θ, ρ sin θ)`` per bin."""
    return rho * np.cos(theta), rho * np.sin(theta)


def bin_gains(c: np.ndarray, s: np.ndarray, theta: np.ndarray, n_steps: int,
              rho: float = 1.0, bits: int = 0) -> np.ndarray:
    """``g_k`` of the module docstring (complex), relative to the ideal ``ρ``-window gain.

    Examples
    --------
    >>> import numpy as np
    >>> th = np.array([0.3])
    >>> float(abs(bin_gains(np.cos(th), np.sin(th), th, 64))[0].round(12))
    1.0
    """
    q = (np.asarray(c) + 1j * np.asarray(s)) / 2.0 ** bits * np.exp(-1j * np.asarray(theta))
    return _geometric(q, n_steps) / _geometric(np.asarray(rho, complex), n_steps)


def _geometric(q: np.ndarray, n: int) -> np.ndarray:
    """``Σ_{j=1}^{n} q^j`` (``n`` where ``q = 1``)."""
    q = np.asarray(q, np.complex128)
    near = np.abs(q - 1) < 1e-12
    safe = np.where(near, 0.5, q)
    out = safe * (1 - safe ** n) / (1 - safe)
    return np.where(near, n * (1 + (n + 1) / 2 * (q - 1)), out)


def fixed_coefficients(theta: np.ndarray, rho: float, bits: int, *,
                       n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Whole ``(C, S)`` per bin with ``C² + S² ≤ (ρ 2^F)²`` and the least drift.

    Parameters
    ----------
    theta : ndarray
        Bin angles (rad per step).
    rho : float
        Decay per step (1: none).
    bits : int
        Fraction bits ``F``.
    n_steps : int
        Input steps ``N`` the drift is judged over.

    Returns
    -------
    (ndarray, ndarray)
        Whole numbers as float64.
    """
    r = rho * 2.0 ** bits
    c0, s0 = np.rint(r * np.cos(theta)), np.rint(r * np.sin(theta))
    off = np.arange(-_REACH, _REACH + 1, dtype=np.float64)
    dc, ds = (a.ravel() for a in np.meshgrid(off, off, indexing="ij"))
    c = c0[None, :] + dc[:, None]
    s = s0[None, :] + ds[:, None]
    cost = np.abs(1.0 - bin_gains(c, s, np.broadcast_to(theta, c.shape), n_steps, rho=rho,
                                  bits=bits))
    cost[np.hypot(c, s) > r] = np.inf  # never a growing state
    best = np.argmin(cost, axis=0)
    cols = np.arange(theta.size)
    return c[best, cols], s[best, cols]


def drift_report(c: np.ndarray, s: np.ndarray, theta: np.ndarray, *, n_steps: int,
                 rho: float, bits: int, full_state: float) -> dict:
    """The drift bounds of one resonator layer (JSON-able, for the report).

    ``gain_drift``: ``max_k |1 − g_k|``; ``phase_drift_rad``: largest ``N·|arg â_k − θ_k|``;
    ``truncation``: ``N/√2`` rounding units over the full-scale state ``full_state``.
    """
    g = bin_gains(c, s, theta, n_steps, rho=rho, bits=bits)
    ang = np.angle((c + 1j * s) * np.exp(-1j * theta))
    trunc = float(n_steps / np.sqrt(2.0) / full_state) if bits and full_state else 0.0
    return {"coef_bits": bits, "n_steps": n_steps, "rho": rho,
            "gain_drift": float(np.max(np.abs(1.0 - g))),
            "phase_drift_rad": float(n_steps * np.max(np.abs(ang))),
            "truncation": trunc,
            "bound": float(np.max(np.abs(1.0 - g))) + trunc}
