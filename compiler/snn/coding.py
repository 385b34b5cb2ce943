"""Encoders (values → spikes) and decoders (spikes → values) at a network's ports.

An :class:`Encoder` turns an input array into the spikes of a source
population; a :class:`Decoder` reads a population's spikes or membrane back
into values.  Both name a *port* (the key of ``simulate``'s inputs/outputs)
and the radar-IR node they stand for.

The value codes they use are in :mod:`compiler.snn.codes` (latency and rate
codes, dither) and :mod:`compiler.snn.stream`; how signed and complex values
are spread over a trailing ``part`` axis (an encoder's ``split``, a decoder's
``combine``) and the per-input normalisation are in :mod:`compiler.snn.parts`.
This module re-exports both, so ``compiler.snn.coding`` still names every one.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from compiler.snn.codes import FrozenModel, LatencyCode, RateCode, dither_offsets
from compiler.snn.parts import (
    N_PARTS,
    PartLayout,
    combine_parts,
    normalize_values,
    split_values,
)
from compiler.snn.stream import StreamCode
from ir.errors import NetworkError

__all__ = [
    "LatencyCode",
    "RateCode",
    "Encoder",
    "Decoder",
    "PartLayout",
    "split_values",
    "combine_parts",
    "normalize_values",
    "dither_offsets",
    "N_PARTS",
]

#: Deprecated alias of :data:`PartLayout` (the old name clashed with the Split pass).
Split = PartLayout

Code = LatencyCode | RateCode | StreamCode


class Encoder(FrozenModel):
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
    split: PartLayout = "none"
    node: str = ""
    normalize_axes: tuple[str, ...] = ()
    saturate: bool = False


class Decoder(FrozenModel):
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
    combine: PartLayout = "none"
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
        sizes = list(shape.values())
        k = axes.index(self.gain_axis)
        g = np.asarray(self.gains, dtype=np.float64)
        # one run of the gain axis (each gain repeated over the axes after it), then that
        # run repeated over the axes before it: copies with long inner loops
        run = np.broadcast_to(g[:, None], (len(g), int(np.prod(sizes[k + 1:])))).ravel()
        return np.tile(run, int(np.prod(sizes[:k])))

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
