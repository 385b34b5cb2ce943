r"""Charging schedules of the time-coded motifs: constant (the paper's) and companding.

After its silent stage a ramp neuron holds the membrane ``V`` (its value in
membrane units).  During the charging window of ``n`` steps the input is cut
and a bias ``b_i`` is added each step; with the cumulative bias
``B(k) = b_1 + … + b_k`` the neuron fires at charging step ``k`` (``1 … n``,
absolute step ``start + k − 1``) the first time

.. math:: V + B(k) \ge v_{th}, \qquad v_{th} = B(n) + b_n / 2 .

So a spike at ``k`` says ``V ∈ [v_th − B(k), v_th − B(k−1))`` and decodes to the
middle of that interval, ``level_k = v_th − (B(k) + B(k−1))/2``; no spike says
``V < b_n/2`` and decodes to 0 (the negative half of a ± pair).  The error is at
most half the local step, ``b_k/2``, below the saturation level ``level_1``.

* **constant** (``b_k = b``): ``level_k = b·(n + 1 − k)``, linear in the spike
  step — a downstream time-coded layer reads it directly, integrating until the
  window end ``E = start + n``: ``E − t_s = level/b``.
* **companding** (``b`` decreasing over a few piecewise-constant phases): large
  values get coarse steps and the many small ones fine steps; decoding is the
  exact table of levels.  Picked when it lowers the mean squared error on the
  calibration values (:func:`choose_schedule`).

Biases are dyadic (:func:`dyadic_ceil`), so every level is exact.

Examples
--------
>>> s = constant_schedule(4, v_full=8.0)
>>> s.biases, s.v_th, s.levels().tolist()
((2.0,), 9.0, [8.0, 6.0, 4.0, 2.0])
>>> s.decode(np.array([8.4, 2.9, 0.9, -3.0])).tolist()
[8.0, 2.0, 0.0, 0.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ir.errors import CompileError

__all__ = [
    "ChargingSchedule",
    "constant_schedule",
    "companding_schedule",
    "log_schedule",
    "noise_error_db",
    "LOG_DYNAMIC_RANGE",
    "choose_schedule",
    "dyadic_ceil",
    "bias_ceil",
    "COMPANDING_RATIOS",
    "GUARD_MIN_RATIO",
    "GUARD_RATIO",
    "guard_steps",
    "with_guard",
]

#: Bias ratios between successive companding phases tried by :func:`choose_schedule`.
COMPANDING_RATIOS = (0.7, 0.5, 0.35, 0.25)

#: Ratio of the top to the bottom level of a ``log`` read-out (2^20, 120 dB): with 256
#: steps each level is 5.6 % above the next (±2.8 %, −31 dB of error at every level).
LOG_DYNAMIC_RANGE = float(2 ** 20)

#: Default guard of a host-decoded layer: values up to this factor above the calibrated
#: full scale (24 dB) are coded coarsely instead of clipped (:func:`with_guard`).
GUARD_RATIO = 16.0

#: Where the membrane state cannot hold a :data:`GUARD_RATIO` guard with the full weight
#: width, the guard is halved down to this (18 dB) before weights get coarser; measured on
#: the TI chirps, leave-one-out on loihi2 (RMSE 0.0052 at 8, 0.0104 at 4, 0.0106 at 16
#: with 5-bit weights; ``docs/fourier.md``).
GUARD_MIN_RATIO = 8.0


def dyadic_ceil(x: float, bits: int = 12) -> float:
    """The smallest ``m·2**e ≥ x`` with an integer mantissa ``m < 2**bits`` (``x > 0``).

    Examples
    --------
    >>> dyadic_ceil(3.0), dyadic_ceil(0.3, bits=4), dyadic_ceil(1000.5, bits=4)
    (3.0, 0.3125, 1024.0)
    """
    if not (math.isfinite(x) and x > 0):
        raise CompileError(f"a charging bias must be a positive finite number, got {x}")
    e = math.frexp(x)[1] - bits
    return math.ldexp(math.ceil(math.ldexp(x, -e)), e)


@dataclass(frozen=True)
class ChargingSchedule:
    """Piecewise-constant charging bias: ``biases[i]`` from relative step ``starts[i]``.

    Parameters
    ----------
    n_steps : int
        Length ``n`` of the charging window.
    starts : tuple of int
        Relative first step of each phase (``starts[0] == 0``, increasing, ``< n``).
    biases : tuple of float
        Bias per phase (positive, dyadic).
    """

    n_steps: int
    starts: tuple[int, ...]
    biases: tuple[float, ...]

    @property
    def kind(self) -> str:
        """``"constant"`` for one phase, else ``"companding"``."""
        return "constant" if len(self.biases) == 1 else "companding"

    def per_step(self) -> np.ndarray:
        """The bias of each charging step ``k = 1 … n`` (length ``n``)."""
        idx = np.searchsorted(np.asarray(self.starts), np.arange(self.n_steps), side="right") - 1
        return np.asarray(self.biases, dtype=np.float64)[idx]

    def cumulative(self) -> np.ndarray:
        """``B(k)`` for ``k = 0 … n`` (exact: dyadic partial sums)."""
        return np.concatenate([[0.0], np.cumsum(self.per_step())])

    @property
    def v_th(self) -> float:
        """The threshold ``B(n) + b_n/2``."""
        return float(self.cumulative()[-1] + self.biases[-1] / 2)

    def levels(self) -> np.ndarray:
        """Decoded membrane value of a spike at charging step ``k = 1 … n`` (decreasing)."""
        b = self.cumulative()
        return self.v_th - (b[1:] + b[:-1]) / 2

    def fire_step(self, v: np.ndarray) -> np.ndarray:
        """Charging step index ``k − 1`` (``0 … n−1``) at which membrane ``v`` fires; ``n``: never.

        Examples
        --------
        >>> constant_schedule(4, v_full=8.0).fire_step(np.array([100.0, 6.9, 1.0, 0.5])).tolist()
        [0, 1, 3, 4]
        """
        theta = self.v_th - self.cumulative()[1:]
        return np.searchsorted(-theta, -np.asarray(v, dtype=np.float64), side="left")

    def decode(self, v: np.ndarray) -> np.ndarray:
        """What the neuron reports for membrane ``v``: its level, or 0 without a spike."""
        k = self.fire_step(v)
        return np.where(k < self.n_steps, np.append(self.levels(), 0.0)[k], 0.0)

    def mse(self, v: np.ndarray) -> float:
        """Mean squared decoding error over non-negative membrane values ``v``."""
        v = np.asarray(v, dtype=np.float64)
        return float(np.mean((self.decode(v) - v) ** 2)) if v.size else 0.0

    def describe(self) -> dict:
        """JSON-able description (kind, starts, biases, v_th)."""
        return {"kind": self.kind, "n_steps": self.n_steps, "starts": list(self.starts),
                "biases": list(self.biases), "v_th": self.v_th}


def _check(n_steps: int, v_full: float) -> None:
    if n_steps < 1 or not (math.isfinite(v_full) and v_full > 0):
        raise CompileError(f"charging window needs n_steps >= 1 and a positive full scale; got "
                           f"n_steps={n_steps}, full scale {v_full}")


def bias_ceil(x: float, whole: bool | int = False) -> float:
    """A charging bias ``≥ x``: :func:`dyadic_ceil`, or with ``whole`` the next even whole
    number (≥ 2), so the threshold ``B(n) + b_n/2`` of an integer target is whole too; an
    integer ``whole`` is the target's bias mantissa width: the bias is also ``m·2^e`` with
    ``|m| < 2^{whole−1}`` (as the chip stores it, so the quantize pass keeps it).

    Examples
    --------
    >>> bias_ceil(3.3), bias_ceil(3.3, whole=True), bias_ceil(0.2, whole=True)
    (3.30078125, 4.0, 2.0)
    >>> bias_ceil(84779.0, whole=13)  # 13-bit mantissa: 2650·2^5
    84800.0
    """
    if whole is False:
        return dyadic_ceil(x)
    if not (math.isfinite(x) and x > 0):
        raise CompileError(f"a charging bias must be a positive finite number, got {x}")
    b = float(max(2, 2 * math.ceil(x / 2)))
    if whole is True or whole < 3:
        return b
    return max(b, dyadic_ceil(b, bits=int(whole) - 1))


def constant_schedule(n_steps: int, v_full: float, whole: bool | int = False
                      ) -> ChargingSchedule:
    """The paper's constant bias ``b = dyadic_ceil(v_full / n)`` (top level ``b·n ≥ v_full``);
    ``whole``: the next even whole number (:func:`bias_ceil`).

    Examples
    --------
    >>> constant_schedule(256, v_full=1000.0).biases, constant_schedule(256, 1000.0, True).biases
    ((3.90625,), (4.0,))
    """
    _check(n_steps, v_full)
    return ChargingSchedule(n_steps, (0,), (bias_ceil(v_full / n_steps, whole),))


def companding_schedule(n_steps: int, v_full: float, ratio: float,
                        n_phases: int = 4, whole: bool | int = False) -> ChargingSchedule:
    r"""``n_phases`` equal phases with biases ``b_0·ratio^i`` and top level ``≥ v_full``.

    Examples
    --------
    >>> s = companding_schedule(8, v_full=15.0, ratio=0.5, n_phases=2)
    >>> s.starts, s.biases, s.v_th
    ((0, 4), (2.5, 1.25), 15.625)
    >>> s.levels().tolist()  # steps of 2.5 above 5, of 1.25 below
    [14.375, 11.875, 9.375, 6.875, 5.0, 3.75, 2.5, 1.25]
    """
    _check(n_steps, v_full)
    n_phases = max(1, min(n_phases, n_steps))
    starts = tuple(int(s) for s in np.linspace(0, n_steps, n_phases + 1)[:-1].round())
    lengths = np.diff([*starts, n_steps])
    weights = ratio ** np.arange(n_phases)
    b0 = v_full / float(np.dot(lengths, weights))
    return ChargingSchedule(n_steps, starts, tuple(bias_ceil(b0 * w, whole) for w in weights))


def log_schedule(n_steps: int, v_full: float, dynamic_range: float = LOG_DYNAMIC_RANGE,
                 whole: bool | int = False) -> ChargingSchedule:
    r"""Thresholds that grow geometrically over the whole window: a logarithmic read-out.

    A constant bias resolves ``v_full/n`` everywhere, so a value more than ``≈ 20\log_{10} n``
    dB below the top (48 dB at ``n = 256``) decodes to 0 — the noise floor of a radar
    spectrum whose returns span more. Here the threshold after step ``k`` is
    ``v_{th} r^{k}`` from the bottom level ``v_full/D`` up to ``v_full``,
    ``r = D^{1/(n−1)}``: every value in range decodes within ``±(r − 1)/2`` of itself
    (relative), whatever its level — :func:`with_guard` over the whole window. The host
    decodes the exact table of levels.

    Examples
    --------
    >>> s = log_schedule(8, v_full=128.0, dynamic_range=128.0)  # r = 2: coarse, to read
    >>> s.levels().tolist()
    [144.0, 72.0, 36.0, 18.0, 9.0, 4.5, 2.25, 1.0]
    >>> s.decode(np.array([100.0, 3.0, 0.4])).tolist()
    [144.0, 4.5, 0.0]
    >>> s = log_schedule(256, v_full=1e6)  # the default: 120 dB, within ±2.8 % everywhere
    >>> v = np.array([9e5, 3e3, 10.0])
    >>> bool(np.all(np.abs(s.decode(v) / v - 1) < 0.03))
    True
    """
    _check(n_steps, v_full)
    if n_steps < 2 or not dynamic_range > 1:
        return constant_schedule(n_steps, v_full, whole)
    body = constant_schedule(1, v_full / dynamic_range, whole)
    return with_guard(body, n_steps - 1, dynamic_range, whole)


def noise_error_db(schedule: ChargingSchedule, v: np.ndarray) -> float:
    """Decoding error over the noise cells of ``v`` (``≤ 4·median``), dB re their RMS.

    Examples
    --------
    >>> v = np.r_[np.random.default_rng(0).rayleigh(size=1000), 1e4]
    >>> round(noise_error_db(constant_schedule(256, 1e4), v))  # the noise decodes to 0
    0
    >>> noise_error_db(log_schedule(256, 1e4), v) < -30
    True
    """
    v = np.asarray(v, dtype=np.float64)
    if not v.size:
        return -240.0
    quiet = v <= 4 * float(np.median(v))
    ref = float(np.linalg.norm(v[quiet]))
    err = float(np.linalg.norm(schedule.decode(v[quiet]) - v[quiet]))
    if ref == 0:
        return 0.0 if err > 0 else -240.0
    return float(20 * np.log10(max(err / ref, 1e-12)))


def choose_schedule(n_steps: int, v_full: float, samples: np.ndarray | None, *,
                    mode: str = "auto", min_gain: float = 0.02, whole: bool | int = False
                    ) -> tuple[ChargingSchedule, dict[str, float]]:
    """Pick the charging schedule with the lowest MSE on calibration membrane values.

    Parameters
    ----------
    n_steps : int
        Charging window.
    v_full : float
        Full-scale membrane value.
    samples : ndarray, optional
        Non-negative membrane values from the calibration set (None: constant).
    mode : {"auto", "constant", "companding", "log"}
        ``auto`` keeps the constant bias unless a companding schedule lowers the MSE by
        more than ``min_gain`` (relative); ``companding`` takes the best companding
        candidate; ``log`` the logarithmic one (:func:`log_schedule`), which keeps a
        noise floor more than ≈ 48 dB under the top (at 256 steps) that the others
        decode to 0 — ``motifs="auto"`` tries it when the accuracy contract asks
        (:mod:`compiler.accuracy.select`).
    min_gain : float
        Relative improvement required in ``auto``.
    whole : bool or int
        Even whole-number biases (an integer target: no rounding in the quantize pass);
        an int: also representable with that bias mantissa width (:func:`bias_ceil`).

    Returns
    -------
    schedule : ChargingSchedule
    mse : dict
        MSE per candidate (``constant``, ``companding-<ratio>``).

    Examples
    --------
    Mostly small values: companding wins.

    >>> v = np.r_[np.full(90, 1.3), np.linspace(0, 100, 10)]
    >>> choose_schedule(16, 100.0, v)[0].kind
    'companding'
    >>> choose_schedule(16, 100.0, v, mode="constant")[0].kind
    'constant'
    """
    if mode not in ("auto", "constant", "companding", "log"):
        raise CompileError(f"charging={mode!r} is not a schedule; use 'auto', 'constant', "
                           "'companding' or 'log'")
    candidates = {"constant": constant_schedule(n_steps, v_full, whole)}
    if mode == "log":
        return log_schedule(n_steps, v_full, whole=whole), {}
    if mode != "constant" and samples is not None and n_steps >= 4:
        for r in COMPANDING_RATIOS:
            candidates[f"companding-{r}"] = companding_schedule(n_steps, v_full, r, whole=whole)
    if samples is None:
        return candidates["constant"], {}
    errors = {name: s.mse(samples) for name, s in candidates.items()}
    best = min((n for n in errors if n != "constant"), key=errors.get, default="constant")
    if mode == "constant" or (mode == "auto"
                              and errors[best] >= (1 - min_gain) * errors["constant"]):
        best = "constant"
    return candidates[best], errors


def guard_steps(n_steps: int) -> int:
    """Charging steps a guard takes from a window of ``n_steps``: ``n/16`` (none below 32).

    Examples
    --------
    >>> guard_steps(256), guard_steps(64), guard_steps(16)
    (16, 4, 0)
    """
    return n_steps // 16 if n_steps >= 32 else 0


def with_guard(body: ChargingSchedule, n_guard: int, ratio: float,
               whole: bool | int = False) -> ChargingSchedule:
    r"""``body`` preceded by ``n_guard`` steps whose thresholds grow geometrically to ``ratio``.

    Calibration from other frames cannot promise that a new frame stays below the
    calibrated full scale (a stronger reflector, a closer target).  A guard keeps such
    values instead of clipping them at the body's top: with the body's threshold
    ``v_th`` and ``r = ratio^{1/g}``, guard step ``i = 1 … g`` (the first steps of the
    window, before the body's) has bias

    .. math:: c_i = v_{th}\,(r - 1)\,r^{g - i},

    so a neuron fires at guard step ``j`` when ``V ≥ θ_j = v_{th} + \sum_{i>j} c_i
    = v_{th}\, r^{g-j}``: values from ``v_th`` to ``ratio · v_th`` decode within
    ``±(r − 1)/2`` relative error (``±9 %`` for ``ratio = 16``, ``g = 16``), and the
    body's levels are unchanged (it has ``g`` fewer steps, so its step is ``n/(n − g)``
    times coarser: ``+0.28 dB`` at ``g = n/16``).  Biases are rounded up as the body's
    (:func:`bias_ceil`), so every level stays exact.

    Examples
    --------
    >>> body = constant_schedule(8, v_full=8.0)  # levels 8, 7, …, 1; v_th = 8.5
    >>> g = with_guard(body, 2, ratio=4.0)  # thresholds 8.5, 17 (and 34 = 4 · 8.5)
    >>> g.n_steps, g.biases[:2], g.levels()[:3].tolist()
    (10, (17.0, 8.5), [25.5, 12.75, 8.0])
    >>> g.decode(np.array([40.0, 12.0, 3.2])).tolist()  # 40 > 34 clips to the top level
    [25.5, 12.75, 3.0]
    """
    if n_guard < 1 or not (math.isfinite(ratio) and ratio > 1):
        return body
    v_th = body.v_th
    r = ratio ** (1.0 / n_guard)
    guard = tuple(bias_ceil(v_th * (r - 1) * r ** (n_guard - i), whole)
                  for i in range(1, n_guard + 1))
    return ChargingSchedule(body.n_steps + n_guard,
                            (*range(n_guard), *(n_guard + s for s in body.starts)),
                            (*guard, *body.biases))
