r"""Rotation coefficients of the resonators, periodic renormalisation, and the drift bounds.

Bin ``k`` rotates by ``a_k = ρ e^{iθ_k}`` per step.  In floating point ``a_k`` is exact
to rounding.  In fixed point (``F`` fraction bits, the Loihi decay format of 12 bits
by default, option ``resonator_coef_bits``) it is a Gaussian integer ``â = (C + iS)/2^F``
with ``|C|, |S| ≤ 2^F``, and sample ``n`` of an ``N``-step stream reaches the state with
the product ``P_n`` of the coefficients of steps ``n … N−1`` instead of ``a^{N−n}``.  Its
relative *weight error* ``ε_n = P_n / a^{N−n} − 1`` bounds every output: for inputs
``|x[n]| ≤ x_max``, ``|Δz_k| ≤ x_max Σ_n |ε_n| ≤ N x_max · rms_n ε_n``, i.e. at most
``rms ε`` of the full-scale bin ``N x_max`` — the ``weight_error`` of :func:`drift_report`.

**Without renormalisation** every step uses ``â``: ``P_n = â^{N−n}`` and the error grows
with ``N`` (``≈ N|â/a − 1|/2``; 0.14 at ``N = 1024`` with 12 bits).
:func:`fixed_coefficients` picks, among the lattice points within 3 units of
``2^F ρ e^{iθ}``, the least drift subject to ``|â| ≤ ρ`` (the state never grows).

**Periodic renormalisation** (option ``resonator_renorm``; :func:`renormalised_coefficients`):
the steps are cut into blocks of ``M`` aligned to the stream's last step, and the last step
of every block uses a second coefficient ``ĉ ≈ a^M / â^{M−1}`` (rounded to the same
format), so each block's product ``R = â^{M−1} ĉ`` equals ``a^M`` to about one rounding of
``ĉ``.  A sample ``m + 1`` steps before its block's end, ``b`` whole blocks before the
stream's end, sees ``P = â^m ĉ R^b``: the error is ``≈ M|â/a − 1| + B|R/a^M − 1|`` with
``B = N/M`` blocks instead of ``N|â/a − 1|`` — about ``2√N`` roundings instead of ``N``.
``â`` may then lie just outside the unit circle (``|â|^{M−1} ≤`` :data:`BLOCK_GROWTH`)
while every block's product keeps ``|R| ≤ ρ^M``: the state never grows over a block.

With ``A = â/a``, ``E = ĉ/a`` (``E = A`` without renormalisation), ``R = A^{M−1}E``,
``N = BM + L`` and ``G(q, m) = Σ_{j<m} q^j``, the two sums the bounds need are

.. math::

    Σ_n P_n/a^{N−n} &= E\,G(A, M)\,G(R, B) + E\,G(A, L)\,R^B \\
    Σ_n |P_n/a^{N−n}|^2 &= |E|^2 G(|A|^2, M)\,G(|R|^2, B) + |E|^2 G(|A|^2, L)\,|R|^{2B}

so ``rms ε = \sqrt{Σ|P|^2/N − 2\,\mathrm{Re}\,Σ P/N + 1}`` costs a few powers per bin.
The rounding of each rotation adds at most half a unit per component and step, so after
``N`` steps a state differs from the exact product by at most ``N/√2`` units (the
``truncation`` term).  Where a read-out is decoded on the host, the known gain ``|g_k|``
of each bin (``g_k = Σ_n P_n e^{−i(N−n)θ_k} / Σ_j ρ^j``) is divided out.

Examples
--------
>>> import numpy as np
>>> c, s = fixed_coefficients(np.array([0.0, np.pi / 2]), 1.0, 12, n_steps=1024)
>>> c.tolist(), s.tolist()
([4096.0, 0.0], [0.0, 4096.0])
>>> th = 2 * np.pi * np.arange(1, 512) / 1024
>>> plain = drift_report(*fixed_coefficients(th, 1.0, 12, n_steps=1024), th, n_steps=1024,
...                      rho=1.0, bits=12, full_state=0)
>>> r = renormalised_coefficients(th, 1.0, 12, n_steps=1024, block=32)
>>> renorm = drift_report(r.c, r.s, th, n_steps=1024, rho=1.0, bits=12, full_state=0, renorm=r)
>>> round(plain["weight_error"], 2), round(renorm["weight_error"], 3)
(0.14, 0.007)
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["CHIP_COEF_BITS", "BLOCK_GROWTH", "Renorm", "bin_angles", "float_coefficients",
           "fixed_coefficients", "renormalised_coefficients", "best_renorm", "bin_gains",
           "weight_errors", "drift_report"]

#: Fraction bits of a chip's rotation coefficients: Lava's bit-accurate resonate-and-fire
#: model (``lava.proc.rf``, the fixed-point model also used for Loihi 2) holds ``sin_decay``
#: and ``cos_decay`` as 12-bit integers applied with a right shift of 12 — the only
#: published format; wider coefficients are the user's assumption (``resonator_coef_bits``).
CHIP_COEF_BITS = 12

#: Largest transient growth within a renormalised block, ``|â|^{M−1}`` (the state is scaled
#: to a quarter of its range at full scale, so 1 % is far inside it).
BLOCK_GROWTH = 1.01

_REACH = 3


class Renorm(NamedTuple):
    """Coefficients of a renormalised resonator layer (all whole numbers, float64).

    ``c, s``: the step coefficient ``â`` per bin; ``c_end, s_end``: the block-end
    coefficient ``ĉ``; ``block``: ``M`` steps per block (aligned to the last input step).
    """

    c: np.ndarray
    s: np.ndarray
    c_end: np.ndarray
    s_end: np.ndarray
    block: int


def bin_angles(freqs: np.ndarray, n_fft: int) -> np.ndarray:
    """``θ_k = 2π f_k / N`` (rad per step) of bins at DFT frequencies ``f_k``."""
    return 2.0 * np.pi * np.asarray(freqs, np.float64) / n_fft


def float_coefficients(theta: np.ndarray, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """``(ρ cos θ, ρ sin θ)`` per bin."""
    return rho * np.cos(theta), rho * np.sin(theta)


def _power_minus_one(d: np.ndarray, n: int) -> np.ndarray:
    """``(1 + d)^n − 1`` to float64's relative precision, also for ``|d| ≪ 1/n``.

    ``1 − q^n`` from ``q^n`` loses every digit below ``|n d|``; through
    ``n log(1 + d)`` and ``expm1`` nothing cancels (``log1p`` and ``expm1`` on the real
    and imaginary parts separately: numpy's complex ones are not accurate near 0).
    """
    x, y = d.real, d.imag
    with np.errstate(divide="ignore"):  # q = 0: log 0 = −inf, and (1 + d)^n − 1 = −1
        lr = 0.5 * np.log1p(2.0 * x + x * x + y * y) * n   # n log|1 + d|
    li = np.arctan2(y, 1.0 + x) * n                    # n arg(1 + d)
    cos_m1 = -2.0 * np.sin(li / 2.0) ** 2
    return np.expm1(lr) * np.cos(li) + cos_m1 + 1j * np.exp(lr) * np.sin(li)


def _g0(q: np.ndarray, n: int) -> np.ndarray:
    """``G(q, n) = Σ_{j=0}^{n−1} q^j``, as ``((1 + d)^n − 1)/d`` with ``d = q − 1``.

    Examples
    --------
    >>> import numpy as np
    >>> g = _g0(np.array([1.0, 1 + 1e-13, 2.0]), 3)
    >>> np.allclose(g, [3.0, 3.0 + 3e-13, 7.0], rtol=1e-15, atol=0)
    True
    """
    d = np.asarray(q, np.complex128) - 1.0
    if n == 0:
        return np.zeros_like(d)
    zero = d == 0
    safe = np.where(zero, 1.0, d)
    return np.where(zero, float(n), _power_minus_one(safe, n) / safe)


def _geometric(q: np.ndarray, n: int) -> np.ndarray:
    """``Σ_{j=1}^{n} q^j``."""
    q = np.asarray(q, np.complex128)
    return q * _g0(q, n)


def _factors(c, s, theta, bits: int, renorm: Renorm | None, n_steps: int):
    """``(A, E, M)``: step and block-end coefficients over ``e^{iθ}``, and the block."""
    turn = np.exp(-1j * np.asarray(theta)) / 2.0 ** bits
    a = (np.asarray(c) + 1j * np.asarray(s)) * turn
    if renorm is None or renorm.block <= 0:
        return a, a, n_steps
    return a, (np.asarray(renorm.c_end) + 1j * np.asarray(renorm.s_end)) * turn, renorm.block


def _sums(a: np.ndarray, e: np.ndarray, n: int, block: int) -> tuple[np.ndarray, np.ndarray]:
    """``(Σ_n P_n, Σ_n |P_n|²)`` over the ``n`` samples (the module docstring)."""
    n_blocks, rest = divmod(n, block)
    r = a ** (block - 1) * e
    s1 = e * (_g0(a, block) * _g0(r, n_blocks) + _g0(a, rest) * r ** n_blocks)
    a2, e2, r2 = (np.abs(v) ** 2 for v in (a, e, r))
    s2 = e2 * (_g0(a2, block) * _g0(r2, n_blocks) + _g0(a2, rest) * r2 ** n_blocks)
    return s1, s2.real


def bin_gains(c: np.ndarray, s: np.ndarray, theta: np.ndarray, n_steps: int,
              rho: float = 1.0, bits: int = 0, renorm: Renorm | None = None) -> np.ndarray:
    """``g_k`` (complex): bin ``k``'s response to its own frequency over the ideal ``ρ``-window.

    Examples
    --------
    >>> import numpy as np
    >>> th = np.array([0.3])
    >>> float(abs(bin_gains(np.cos(th), np.sin(th), th, 64))[0].round(12))
    1.0
    """
    a, e, block = _factors(c, s, theta, bits, renorm, n_steps)
    return _sums(a, e, n_steps, block)[0] / _geometric(np.asarray(rho, complex), n_steps)


def weight_errors(c: np.ndarray, s: np.ndarray, theta: np.ndarray, n_steps: int,
                  rho: float = 1.0, bits: int = 0, renorm: Renorm | None = None) -> np.ndarray:
    """``rms_n |P_n / a^{N−n} − 1|`` per bin (the module docstring), ``a = ρ e^{iθ}``.

    From the two sums, whose geometric series go through ``expm1``/``log1p`` (nothing
    cancels where ``|â| = ρ`` almost exactly): ``rms²`` is exact to about ``1e-15``, so
    ``rms`` to about ``1e-8`` near zero (the square root of float64's rounding).

    Examples
    --------
    >>> import numpy as np
    >>> th = np.array([0.3])
    >>> float(weight_errors(np.cos(th), np.sin(th), th, 64)[0].round(6))  # to ~1e-8
    0.0
    """
    a, e, block = _factors(c, s, theta, bits, renorm, n_steps)
    s1, s2 = _sums(a / rho, e / rho, n_steps, block)
    return np.sqrt(np.maximum(s2 / n_steps - 2.0 * s1.real / n_steps + 1.0, 0.0))


def _lattice(c0: np.ndarray, s0: np.ndarray, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """Lattice points within ``reach`` units of ``(c0, s0)``: a new leading axis."""
    off = np.arange(-reach, reach + 1, dtype=np.float64)
    dc, ds = (a.ravel() for a in np.meshgrid(off, off, indexing="ij"))
    grow = (slice(None),) + (None,) * np.ndim(c0)
    return np.rint(c0)[None] + dc[grow], np.rint(s0)[None] + ds[grow]


def fixed_coefficients(theta: np.ndarray, rho: float, bits: int, *,
                       n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Whole ``(C, S)`` per bin with ``C² + S² ≤ (ρ 2^F)²`` and the least drift ``|1 − g|``.

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
    c, s = _lattice(r * np.cos(theta), r * np.sin(theta), _REACH)
    cost = np.abs(1.0 - bin_gains(c, s, np.broadcast_to(theta, c.shape), n_steps, rho=rho,
                                  bits=bits))
    cost[np.hypot(c, s) > r] = np.inf  # never a growing state
    best = np.argmin(cost, axis=0)
    cols = np.arange(theta.size)
    return c[best, cols], s[best, cols]


def _candidate_errors(c, s, ce, se, theta, n_steps: int, rho: float, bits: int, block: int):
    """:func:`weight_errors` of every candidate ``(â, ĉ)`` — step coefficients ``(c, s)``
    of shape ``(P, K)``, block-end ones ``(ce, se)`` of shape ``(E, P, K)`` — and the
    candidates' ``(A, E)`` factors.

    The same arithmetic, element for element, as ``weight_errors`` on the candidates
    broadcast to ``(E, P, K)``; what depends on ``â`` alone (its turn, its powers and its
    geometric sums) is computed once per ``(P, K)`` instead of ``E`` times.
    """
    turn = np.exp(-1j * np.asarray(theta)) / 2.0 ** bits
    a_rel = (np.asarray(c) + 1j * np.asarray(s)) * turn
    e_rel = (np.asarray(ce) + 1j * np.asarray(se)) * turn
    a, e = a_rel / rho, e_rel / rho
    n_blocks, rest = divmod(n_steps, block)
    r = a ** (block - 1) * e
    s1 = e * (_g0(a, block) * _g0(r, n_blocks) + _g0(a, rest) * r ** n_blocks)
    a2, e2, r2 = (np.abs(v) ** 2 for v in (a, e, r))
    s2 = e2 * (_g0(a2, block) * _g0(r2, n_blocks) + _g0(a2, rest) * r2 ** n_blocks)
    cost = np.sqrt(np.maximum(s2.real / n_steps - 2.0 * s1.real / n_steps + 1.0, 0.0))
    return cost, a_rel, e_rel


def renormalised_coefficients(theta: np.ndarray, rho: float, bits: int, *, n_steps: int,
                              block: int) -> Renorm:
    """Step and block-end coefficients with the least weight error for blocks of ``block``.

    Searches ``â`` within 3 units of ``2^F a`` and, for each, ``ĉ`` within 1 unit of
    ``2^F a^M/â^{M−1}`` (and ``ĉ = â``: no correction), keeping ``|C|, |S| ≤ 2^F`` (the
    coefficient format), ``|â|^{M−1} ≤`` :data:`BLOCK_GROWTH` and ``|R| ≤ ρ^M``.

    Examples
    --------
    >>> import numpy as np
    >>> r = renormalised_coefficients(np.array([0.0]), 1.0, 12, n_steps=64, block=16)
    >>> r.c.tolist(), r.c_end.tolist(), r.block
    ([4096.0], [4096.0], 16)
    """
    theta = np.asarray(theta, np.float64)
    one, k = 2.0 ** bits, theta.size
    c, s = _lattice(one * rho * np.cos(theta), one * rho * np.sin(theta), _REACH)  # (49, K)
    a_hat = (c + 1j * s) / one
    target = (rho * np.exp(1j * theta)) ** block / a_hat ** (block - 1) * one
    ce, se = _lattice(target.real, target.imag, 1)  # (9, 49, K)
    ce, se = np.concatenate([ce, c[None]]), np.concatenate([se, s[None]])
    cost, a_rel, e_rel = _candidate_errors(c, s, ce, se, theta, n_steps, rho, bits, block)
    bad = ((np.maximum(np.abs(c), np.abs(s)) > one)[None]
           | (np.maximum(np.abs(ce), np.abs(se)) > one)
           | (np.abs(a_hat)[None] ** (block - 1) > BLOCK_GROWTH)
           | (np.abs(a_rel ** (block - 1) * e_rel) > rho ** block * (1 + 1e-12)))
    cost[bad | ~np.isfinite(cost)] = np.inf
    flat = cost.reshape(-1, k)
    best = np.argmin(flat, axis=0)
    i_end, i_step = np.unravel_index(best, cost.shape[:2])
    cols = np.arange(k)
    return Renorm(c[i_step, cols], s[i_step, cols], ce[i_end, i_step, cols],
                  se[i_end, i_step, cols], block)


def best_renorm(theta: np.ndarray, rho: float, bits: int, *, n_steps: int,
                blocks: tuple[int, ...] | None = None) -> Renorm:
    """The renormalisation with the least largest weight error over block lengths.

    ``blocks`` defaults to the powers of two from 4 to ``N``; the plain coefficients
    (:func:`fixed_coefficients`, ``block = 0``) are a candidate too, so renormalising never
    makes a layer worse by this measure.
    """
    c, s = fixed_coefficients(theta, rho, bits, n_steps=n_steps)
    best = Renorm(c, s, c, s, 0)
    worst = float(np.max(weight_errors(c, s, theta, n_steps, rho=rho, bits=bits)))
    if blocks is None:
        blocks = tuple(2 ** j for j in range(2, max(2, int(np.log2(max(n_steps, 1)))) + 1))
    for block in blocks:
        if not 2 <= block <= n_steps:
            continue
        r = renormalised_coefficients(theta, rho, bits, n_steps=n_steps, block=block)
        err = float(np.max(weight_errors(r.c, r.s, theta, n_steps, rho=rho, bits=bits,
                                         renorm=r)))
        if err < worst:
            best, worst = r, err
    return best


def drift_report(c: np.ndarray, s: np.ndarray, theta: np.ndarray, *, n_steps: int,
                 rho: float, bits: int, full_state: float, renorm: Renorm | None = None) -> dict:
    """The drift bounds of one resonator layer (JSON-able, for the report).

    ``weight_error``: ``max_k rms_n ε_n`` (a bound on any output's error over the
    full-scale bin); ``gain_drift``: ``max_k |1 − g_k|``; ``phase_drift_rad``: the largest
    phase error of any sample's weight; ``truncation``: ``N/√2`` rounding units over the
    full-scale state ``full_state``; ``bound`` = ``weight_error + truncation``;
    ``renorm_steps``: ``M`` (0: no renormalisation).
    """
    g = bin_gains(c, s, theta, n_steps, rho=rho, bits=bits, renorm=renorm)
    w = weight_errors(c, s, theta, n_steps, rho=rho, bits=bits, renorm=renorm)
    a, e, block = _factors(c, s, theta, bits, renorm, n_steps)
    alpha, gamma = np.angle(a), np.angle(e)
    beta = np.angle(a ** (block - 1) * e)
    n_blocks, rest = divmod(n_steps, block)
    corners = [m * alpha + gamma + b * beta for m in (0, block - 1) for b in (0, n_blocks - 1)]
    if rest:
        corners += [m * alpha + gamma + n_blocks * beta for m in (0, rest - 1)]
    phase = float(np.max(np.abs(corners))) if np.size(theta) else 0.0
    trunc = float(n_steps / np.sqrt(2.0) / full_state) if bits and full_state else 0.0
    weight = float(np.max(w)) if np.size(w) else 0.0
    return {"coef_bits": bits, "n_steps": n_steps, "rho": rho,
            "renorm_steps": int(renorm.block) if renorm is not None else 0,
            "weight_error": weight,
            "gain_drift": float(np.max(np.abs(1.0 - g))) if np.size(g) else 0.0,
            "phase_drift_rad": phase, "truncation": trunc, "bound": weight + trunc}
