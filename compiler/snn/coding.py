r"""Encoders (values → spikes) and decoders (spikes → values) at a network's ports.

An :class:`Encoder` turns an input array into the spikes of a source
population; a :class:`Decoder` reads a population's spikes or membrane back
into values.  Both name a *port* (the key of ``simulate``'s inputs/outputs)
and the radar-IR node they stand for.

Codes
-----
Linear latency (time-to-first-spike), larger values earlier:

.. math:: t = t_{min} + \frac{x_{max} - x}{x_{max} - x_{min}} (T - t_{min})

Log latency uses ``log x`` in place of ``x`` (``x_min > 0``).  Values are
clipped to ``[x_min, x_max]``; the time is rounded to a step (``nearest`` or
``floor``); a spike at ``t = T`` falls outside the window ``[0, T)`` and is not
emitted (for the ramp neurons that is exactly a zero contribution).

Regular rate code with deterministic phase: the rate is
``r = r_max (x - x_min)/(x_max - x_min)`` spikes per step and a spike falls on
step ``t`` iff ``floor((t+1)·r + φ) > floor(t·r + φ)``.

Per-input normalisation (``Encoder.normalize_axes``): before splitting, each
slice over those axes is divided by its largest ``max(|Re x|, |Im x|)``
(:func:`normalize_values`; an all-zero slice stays zero), so every chirp or
frame uses the code's whole range; decoded outputs are then in those
normalised units.

Value splitting (``split``) puts signed or complex values on a trailing
``part`` axis: ``re_im`` → (Re, Im); ``signed`` → (relu(x), relu(−x));
``re_im_signed`` → (relu Re, relu −Re, relu Im, relu −Im).  Decoders'
``combine`` undoes it.

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
from pydantic import BaseModel, ConfigDict, Field, model_validator

from compiler.snn.stream import StreamCode
from ir.errors import NetworkError

__all__ = [
    "LatencyCode",
    "RateCode",
    "Encoder",
    "Decoder",
    "Split",
    "split_values",
    "combine_parts",
    "normalize_values",
    "dither_offsets",
    "N_PARTS",
]

Split = Literal["none", "re_im", "signed", "re_im_signed"]

#: Size of the trailing ``part`` axis each split adds (``none`` adds no axis).
N_PARTS: dict[str, int] = {"none": 0, "re_im": 2, "signed": 2, "re_im_signed": 4}


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class LatencyCode(_Frozen):
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
        return self.t_min + (hi - x) / (hi - lo) * (self.t_max - self.t_min)

    def spike_steps(self, x: np.ndarray) -> np.ndarray:
        """Integer spike steps; ``t_max`` means no spike inside the window.

        Rounding ``nearest`` is half-to-even (numpy's ``rint``); ``dither`` offsets each
        position of the last axis (the encoders pass ``(frames, values)``, a frame's
        parts flattened in C order).
        """
        t = self.spike_times(x)
        if self.rounding == "dither":
            t = t + dither_offsets(t.shape[-1] if t.ndim else 1).reshape(t.shape[-1:])
        steps = np.rint(t) if self.rounding == "nearest" else np.floor(t)
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


class RateCode(_Frozen):
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


Code = LatencyCode | RateCode | StreamCode


class Encoder(_Frozen):
    """Feeds an input port's values into a source population.

    Parameters
    ----------
    port : str
        Input name (the key in ``simulate``'s ``inputs``).
    population : str
        The source population that emits the spikes; its shape is the value
        shape plus a trailing ``part`` axis when ``split`` adds one.
    code : LatencyCode, RateCode or StreamCode
        How values become spikes (a stream code replaces its axis by a ``bit`` axis in
        the population, :mod:`compiler.snn.stream`).
    split : {"none", "re_im", "signed", "re_im_signed"}
        How signed/complex values are spread over the ``part`` axis.
    node : str
        The radar-IR node the port stands for.
    normalize_axes : tuple of str
        Value axes to normalise over at run time (per-input calibration, see
        :func:`normalize_values`); empty: values are encoded as given.
    saturate : bool
        The code's top was chosen below the calibration maximum on purpose (e.g. a
        CFAR code at a calibration quantile < 1): values above it are part of the
        code — clipped and counted, never refused by the out-of-range policy.
    """

    port: str
    population: str
    code: LatencyCode | RateCode | StreamCode = Field(discriminator="type")
    split: Split = "none"
    node: str = ""
    normalize_axes: tuple[str, ...] = ()
    saturate: bool = False


class Decoder(_Frozen):
    r"""Reads values back from a population at an output port.

    Decoder kinds (``y`` per neuron, before ``combine``):

    ``spike_time``  ``y = scale·(t_ref − t_s) + offset`` at the first spike step
                    ``t_s``; ``missing`` where the neuron never fired.
    ``count``       ``y = scale·count + offset`` (number of spikes in the frame).
    ``membrane``    ``y = scale·v + offset`` at the end of the frame.
    ``spiked``      ``y = 1.0`` where the neuron fired, else ``0.0`` (detection masks).
    ``spike_table`` ``y = scale·table[t_s − t_ref] + offset`` (a non-uniform time code,
                    e.g. a companding charging schedule); ``missing`` without a spike
                    or outside the table.

    Per-index gains (``gain_axis``, ``gains``): the population carries the value
    at index ``i`` of axis ``gain_axis`` multiplied by ``gains[i]`` (a time-coded
    stage scaled each bin to use its whole latency window), so every decoded
    value except ``missing`` is divided by it:

    .. math:: y_{\ldots i \ldots} = \frac{\mathrm{scale}\cdot(t_{ref} - t_s)
              + \mathrm{offset}}{g_i}\quad(\texttt{spike\_time}; \text{likewise the
              other kinds but } \texttt{spiked})

    before ``combine``.  The axis is a population axis other than ``part`` and
    ``len(gains)`` is its size (checked against the population by
    :func:`backends.reference.decoding.check_decoders`).

    Parameters
    ----------
    port, population, node : str
        Output name, the population read and the radar-IR node it stands for.
    kind : {"spike_time", "count", "membrane", "spiked", "spike_table"}
    scale, offset, t_ref, missing : float
        The affine map above (``missing`` for ``spike_time`` only).
    combine : {"none", "re_im", "signed", "re_im_signed"}
        Folds the trailing ``part`` axis: ``re_im`` → ``y0 + 1j·y1``; ``signed`` →
        ``y0 − y1``; ``re_im_signed`` → ``(y0 − y1) + 1j·(y2 − y3)``.
    table : tuple of float
        The levels of a ``spike_table`` decoder.
    gain_axis : str or None
        The population axis the gains run along (None: no gains).
    gains : tuple of float
        Positive finite gain per index of ``gain_axis`` (empty without an axis).

    Examples
    --------
    >>> d = Decoder(port="y", population="p", kind="count", scale=2.0, gain_axis="range",
    ...             gains=(1.0, 4.0))
    >>> d.neuron_gains({"doppler": 2, "range": 2}).tolist()  # memory order, range fastest
    [1.0, 4.0, 1.0, 4.0]
    """

    port: str
    population: str
    kind: Literal["spike_time", "count", "membrane", "spiked", "spike_table"]
    scale: float = 1.0
    offset: float = 0.0
    t_ref: float = 0.0
    missing: float = 0.0
    combine: Split = "none"
    node: str = ""
    table: tuple[float, ...] = ()
    gain_axis: str | None = None
    gains: tuple[float, ...] = ()

    @model_validator(mode="after")
    def _gains(self) -> Decoder:
        if (self.gain_axis is None) != (not self.gains):
            raise ValueError(f"decoder {self.port!r}: gain_axis and gains go together, got "
                             f"gain_axis={self.gain_axis!r} and {len(self.gains)} gains")
        if self.gains and not all(np.isfinite(g) and g > 0 for g in self.gains):
            raise ValueError(f"decoder {self.port!r}: gains must be positive and finite; got "
                             f"{sum(not (np.isfinite(g) and g > 0) for g in self.gains)} "
                             "bad entries")
        if self.gains and self.kind == "spiked":
            raise ValueError(f"decoder {self.port!r}: kind 'spiked' reads no value to divide "
                             "by gains; drop gain_axis/gains")
        return self

    def neuron_gains(self, shape: dict[str, int]) -> np.ndarray | float:
        """Per-neuron gains (flat, memory order) for a population of ``shape``; 1.0 without.

        Raises
        ------
        NetworkError
            If ``gain_axis`` is not in ``shape`` or ``gains`` does not match its size.
        """
        if self.gain_axis is None:
            return 1.0
        axes = list(shape)
        if self.gain_axis not in axes or shape[self.gain_axis] != len(self.gains):
            raise NetworkError(f"decoder {self.port!r}: gain_axis {self.gain_axis!r} with "
                             f"{len(self.gains)} gains does not fit population {self.population!r} "
                             f"of shape {dict(shape)}; give one gain per index of a "
                             "population axis", node=self.port)
        view = [1] * len(axes)
        view[axes.index(self.gain_axis)] = len(self.gains)
        g = np.asarray(self.gains, dtype=np.float64).reshape(view)
        return np.broadcast_to(g, tuple(shape.values())).ravel()

    @model_validator(mode="after")
    def _finite(self) -> Decoder:
        bad = {k: v for k, v in (("scale", self.scale), ("offset", self.offset),
                                 ("t_ref", self.t_ref)) if not np.isfinite(v)}
        if bad:
            raise ValueError(f"decoder {self.port!r}: {bad} must be finite (only `missing` may "
                             "be NaN or infinite)")
        if self.kind == "spike_table" and not (self.table and float(self.t_ref).is_integer()
                                               and np.all(np.isfinite(self.table))):
            raise ValueError(f"decoder {self.port!r}: kind 'spike_table' needs a non-empty "
                             f"finite table and an integer t_ref (its first step), got "
                             f"{len(self.table)} entries and t_ref={self.t_ref}")
        return self

    def table_values(self, first_spike: np.ndarray,
                     gains: np.ndarray | float = 1.0) -> np.ndarray:
        """``spike_table`` decoding of first-spike steps (``-1``: no spike), divided by ``gains``.

        Examples
        --------
        >>> d = Decoder(port="y", population="p", kind="spike_table", table=(4.0, 1.0),
        ...             t_ref=10, scale=0.5, missing=-1.0)
        >>> d.table_values(np.array([10, 11, 12, -1])).tolist()
        [2.0, 0.5, -1.0, -1.0]
        """
        n = len(self.table)
        # one lookup in [missing, scale·table + offset, missing]: index 0 for no spike (or a
        # step before t_ref), n + 1 for a step past the table
        ext = np.empty(n + 2)
        ext[0] = ext[-1] = self.missing
        ext[1:-1] = self.scale * np.asarray(self.table, dtype=np.float64) + self.offset
        first = np.asarray(first_spike, dtype=np.int64)
        index = first - (int(self.t_ref) - 1)
        if int(self.t_ref) < 0:  # else no spike (-1) lands at or below 0 anyway
            index[first < 0] = 0
        np.clip(index, 0, n + 1, out=index)
        value = ext[index]
        if np.isscalar(gains) and gains == 1.0:
            return value
        if np.broadcast_shapes(value.shape, np.shape(gains)) != value.shape:
            value = np.broadcast_to(value, np.broadcast_shapes(value.shape,
                                                               np.shape(gains))).copy()
            index = np.broadcast_to(index, value.shape)
        np.divide(value, gains, out=value, where=(index > 0) & (index <= n))
        return value


def normalize_values(x: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
    """Divide each slice over ``axes`` by its largest ``max(|Re|, |Im|)`` (zero slices stay 0).

    Examples
    --------
    >>> normalize_values(np.array([[2.0, -4.0], [0.0, 0.0]]), axes=(1,)).tolist()
    [[0.5, -1.0], [0.0, 0.0]]
    >>> normalize_values(np.array([3.0 - 6.0j]), axes=(0,)).tolist()
    [(0.5-1j)]
    """
    x = np.asarray(x)
    if not axes:
        return x
    peak = np.maximum(np.abs(np.real(x)), np.abs(np.imag(x))).max(axis=axes, keepdims=True)
    return x / np.where(peak > 0, peak, 1.0)


def split_values(x: np.ndarray, split: Split) -> np.ndarray:
    """Spread values over a trailing ``part`` axis (see the module docstring).

    Examples
    --------
    >>> split_values(np.array([2.0 - 3.0j]), "re_im_signed").tolist()
    [[2.0, 0.0, 0.0, 3.0]]
    """
    x = np.asarray(x)
    if split == "none":
        return x
    re, im = np.real(x).astype(np.float64), np.imag(x).astype(np.float64)
    if split == "re_im":
        parts = (re, im)
    elif split == "signed":
        parts = (np.maximum(re, 0.0), np.maximum(-re, 0.0))
    else:
        parts = (np.maximum(re, 0), np.maximum(-re, 0), np.maximum(im, 0), np.maximum(-im, 0))
    return np.stack(parts, axis=-1)


def combine_parts(y: np.ndarray, combine: Split) -> np.ndarray:
    """Fold a trailing ``part`` axis back into values (inverse of :func:`split_values`).

    Examples
    --------
    >>> combine_parts(split_values(np.array([2.0 - 3.0j]), "re_im_signed"), "re_im_signed")
    array([2.-3.j])
    """
    if combine == "none":
        return y
    if combine == "re_im":
        return y[..., 0] + 1j * y[..., 1]
    if combine == "signed":
        return y[..., 0] - y[..., 1]
    return (y[..., 0] - y[..., 1]) + 1j * (y[..., 2] - y[..., 3])


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
