r"""Spike codes of single values: latency (time-to-first-spike) and regular rate codes.

Linear latency (time-to-first-spike), larger values earlier:

.. math:: t = t_{min} + \frac{x_{max} - x}{x_{max} - x_{min}} (T - t_{min})

Log latency uses ``log x`` in place of ``x`` (``x_min > 0``).  Values are
clipped to ``[x_min, x_max]``; the time is rounded to a step (``nearest``,
``floor`` or ``dither``, :func:`dither_offsets`); a spike at ``t = T`` falls
outside the window ``[0, T)`` and is not emitted (for the ramp neurons that is
exactly a zero contribution).

Regular rate code with deterministic phase: the rate is
``r = r_max (x - x_min)/(x_max - x_min)`` spikes per step and a spike falls on
step ``t`` iff ``floor((t+1)·r + φ) > floor(t·r + φ)``.

The encoders and decoders that use these codes at a network's ports are in
:mod:`compiler.snn.coding` (which re-exports everything here).

Examples
--------
>>> import numpy as np
>>> code = LatencyCode(t_min=0, t_max=10, x_min=0.0, x_max=1.0)
>>> code.spike_steps(np.array([1.0, 0.5, 0.0])).tolist()
[0, 5, 10]
>>> RateCode(x_min=0.0, x_max=1.0, max_rate=0.5).spike_counts(np.array([1.0, 0.5]), 8).tolist()
[4, 2]
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import ConfigDict, Field, model_validator

from ir.errors import NetworkValidationError
from ir.model import CheckedModel

__all__ = ["FrozenModel", "LatencyCode", "RateCode", "dither_offsets"]


class FrozenModel(CheckedModel):
    """Base of the immutable port records: frozen, unknown fields refused."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = NetworkValidationError


class LatencyCode(FrozenModel):
    """Time-to-first-spike code: one spike per value, larger values earlier.

    Parameters
    ----------
    kind : {"linear", "log"}
        Map ``x`` (or ``log x``) linearly onto the window.
    t_min, t_max : int
        Earliest spike step (for ``x_max``) and the window end ``T`` (for ``x_min``;
        a spike at ``T`` is not emitted).
    x_min, x_max : float
        The encoded range; values outside it are clipped.
    rounding : {"nearest", "floor", "dither"}
        How the real-valued time becomes a step; ``dither``: ``floor(t + u_i)`` with
        a fixed offset ``u_i ∈ [0, 1)`` per position ``i`` of the last axis
        (:func:`dither_offsets`) — unbiased (the mean over ``u`` is ``t``), and a
        value repeated at many positions (the static part of a signal over
        chirps) gets independent rounding errors instead of one repeated error.
    """

    type: Literal["latency"] = "latency"
    kind: Literal["linear", "log"] = "linear"
    t_min: int = Field(default=0, ge=0)
    t_max: int = Field(gt=0)
    x_min: float
    x_max: float
    rounding: Literal["nearest", "floor", "dither"] = "nearest"

    @model_validator(mode="after")
    def _ranges(self) -> LatencyCode:
        if not (np.isfinite(self.x_min) and np.isfinite(self.x_max) and self.x_max > self.x_min):
            raise ValueError(f"need finite x_min < x_max, got {self.x_min}, {self.x_max}")
        if self.t_min >= self.t_max:
            raise ValueError(f"need t_min < t_max, got {self.t_min}, {self.t_max}")
        if self.kind == "log" and self.x_min <= 0:
            raise ValueError(f"a log code needs x_min > 0, got {self.x_min}")
        return self

    def spike_times(self, x: np.ndarray) -> np.ndarray:
        """Real-valued spike times ``t`` in ``[t_min, t_max]`` (before rounding)."""
        x = np.clip(np.asarray(x, dtype=np.float64), self.x_min, self.x_max)
        lo, hi = self.x_min, self.x_max
        if self.kind == "log":
            x, lo, hi = np.log(x), np.log(lo), np.log(hi)
        if not isinstance(x, np.ndarray) or x.ndim == 0:
            return self.t_min + (hi - x) / (hi - lo) * (self.t_max - self.t_min)
        # the same operations in place (x is a new array here): no temporaries per frame
        np.subtract(hi, x, out=x)
        x /= hi - lo
        x *= self.t_max - self.t_min
        x += self.t_min
        return x

    def spike_steps(self, x: np.ndarray) -> np.ndarray:
        """Integer spike steps; ``t_max`` means no spike inside the window.

        Rounding ``nearest`` is half-to-even (numpy's ``rint``); ``dither`` offsets each
        position of the last axis (the encoders pass ``(frames, values)``, a frame's
        parts flattened in C order).
        """
        t = self.spike_times(x)
        if self.rounding == "dither":
            t = t + dither_offsets(t.shape[-1] if t.ndim else 1).reshape(t.shape[-1:])
        out = t if isinstance(t, np.ndarray) and t.ndim else None
        steps = np.rint(t, out=out) if self.rounding == "nearest" else np.floor(t, out=out)
        return steps.astype(np.int64)

    def value_of(self, steps: np.ndarray) -> np.ndarray:
        """The value a spike at ``steps`` stands for (the code's inverse).

        Examples
        --------
        >>> LatencyCode(t_max=10, x_min=0.0, x_max=1.0).value_of(np.array([0, 5])).tolist()
        [1.0, 0.5]
        """
        lo, hi = self.x_min, self.x_max
        if self.kind == "log":
            lo, hi = np.log(lo), np.log(hi)
        frac = (np.asarray(steps, np.float64) - self.t_min) / (self.t_max - self.t_min)
        y = hi - frac * (hi - lo)
        return np.exp(y) if self.kind == "log" else y


class RateCode(FrozenModel):
    """Regular spike trains with a deterministic phase.

    Parameters
    ----------
    x_min, x_max : float
        Encoded range; ``x_min`` gives rate 0, ``x_max`` gives ``max_rate``.
    max_rate : float
        Spikes per step at ``x_max`` (at most 1).
    phase : float
        Phase ``φ`` in ``[0, 1)`` of every train.
    """

    type: Literal["rate"] = "rate"
    x_min: float = 0.0
    x_max: float = 1.0
    max_rate: float = Field(default=0.5, gt=0.0, le=1.0)
    phase: float = Field(default=0.0, ge=0.0, lt=1.0)

    @model_validator(mode="after")
    def _ranges(self) -> RateCode:
        if not (np.isfinite(self.x_min) and np.isfinite(self.x_max) and self.x_max > self.x_min):
            raise ValueError(f"need finite x_min < x_max, got {self.x_min}, {self.x_max}")
        return self

    def rates(self, x: np.ndarray) -> np.ndarray:
        """Spikes per step for each value."""
        x = np.clip(np.asarray(x, dtype=np.float64), self.x_min, self.x_max)
        return self.max_rate * (x - self.x_min) / (self.x_max - self.x_min)

    def spikes_at(self, rates: np.ndarray, t: int) -> np.ndarray:
        """Boolean spikes of step ``t`` for trains of the given rates."""
        return np.floor((t + 1) * rates + self.phase) > np.floor(t * rates + self.phase)

    def spike_counts(self, x: np.ndarray, n_steps: int) -> np.ndarray:
        """Spikes in ``n_steps`` steps: ``floor(n·r + φ) - floor(φ)``."""
        r = self.rates(x)
        return (np.floor(n_steps * r + self.phase) - np.floor(self.phase)).astype(np.int64)


def dither_offsets(n: int) -> np.ndarray:
    r"""The fixed dither offsets ``u_0 … u_{n−1} ∈ [0, 1)`` of ``rounding="dither"``.

    ``u_i`` is the top 53 bits of SplitMix64's output for ``i`` (a bijective integer
    hash: the same numbers in any language and numpy version, no random state), so
    the offsets are uniform and uncorrelated between positions.  Re-quantising a
    signal that is already on a grid (ADC codes) with a step that is not a divisor
    of its LSB rounds the part that repeats over chirps the same way in every
    chirp; the chirp sum (the Doppler DFT's zero bin) then adds those errors
    coherently into false zero-Doppler peaks.  With the offsets the error of each
    sample is uniform on ``(−s, s)`` and independent of the value (non-subtractive
    dither: error power ``s²/6`` instead of ``s²/12``, but white).

    Examples
    --------
    >>> u = dither_offsets(100_000)
    >>> bool(u.min() >= 0 and u.max() < 1), round(float(u.mean()), 2)
    (True, 0.5)
    >>> dither_offsets(3).round(4).tolist()
    [0.8833, 0.4315, 0.0264]
    """
    with np.errstate(over="ignore"):
        z = (np.arange(n, dtype=np.uint64) + np.uint64(1)) * np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return (z >> np.uint64(11)).astype(np.float64) * 2.0 ** -53
