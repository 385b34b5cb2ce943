"""The options the lowering rules read, as typed fields of the motif they configure.

Each motif family declares one frozen pydantic model; its fields are compile options
by name (``compile_graph(options={...})``, CLI ``--option``), each with its own
default — every motif names its own step count (:class:`TimeDftOptions` 256,
:class:`FftOptions` 256, :class:`RateOptions` 2000, :class:`CfarOptions` 100; the
option ``time_steps`` overrides them all).  :func:`compiler.compile.motif_settings`
builds every model once from the checked options, before any pass runs (the one place
that reads the options mapping), and the ``lower`` pass hands the
result to the rules (:meth:`LoweringContext.settings_of
<compiler.lowering.context.LoweringContext.settings_of>`): no rule reads an options
mapping.  The same declaration gives ``compile_graph``'s option table
(:data:`compiler.compile.EXTRA_OPTIONS`) and the up-front checks
(:func:`compiler.option_checks.typed_checks`).

Examples
--------
>>> CfarOptions().time_steps, RateOptions().time_steps, CfarOptions(time_steps=64).time_steps
(100, 2000, 64)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from compiler.lowering.charging import GUARD_RATIO

__all__ = ["MOTIF_OPTION_MODELS", "CfarOptions", "FftOptions", "MotifSettings", "RateOptions",
           "ResonatorOptions", "TimeDftOptions", "TimeInputOptions"]

_Finite = Annotated[float, Field(allow_inf_nan=False)]
_Pair = tuple[_Finite, _Finite]
_Quantile = Annotated[float, Field(ge=0, le=1)]
#: Steps per code window: at most 2^31 (a step index is an int64 sum of such windows).
_Steps = Annotated[int, Field(ge=1, le=1 << 31)]
_CONFIG = ConfigDict(frozen=True, extra="ignore")


class TimeInputOptions(BaseModel):
    """Options of the time-coded S-FT's input rounding and read-out (typed fields)."""

    model_config = ConfigDict(frozen=True, extra="ignore")
    input_rounding: Literal["auto", "nearest", "dither"] = Field(
        "auto", description="auto, nearest or dither")
    charging_guard: float = Field(GUARD_RATIO, ge=1, allow_inf_nan=False,
                                  description="a finite number >= 1 (1: no guard)")
    output_spikes: Literal["auto", "time", "graded"] = Field(
        "auto", description="auto, time or graded")
    encoder_headroom: Literal["auto"] | Annotated[float, Field(ge=1, le=2.0 ** 62,
                                                               allow_inf_nan=False)] = Field(
        "auto", description="auto or a number in 1..2^62 (it costs log2 of it in code bits)")


class TimeDftOptions(BaseModel):
    """The time-coded S-FT (``dft``/``linear`` motif ``time``; ``compiler.lowering.dft_time``)."""

    model_config = _CONFIG
    time_steps: _Steps = Field(256, description="an integer >= 1")
    charging: Literal["auto", "constant", "companding", "log"] = Field(
        "auto", description="auto, constant, companding or log")
    stage_gains: Literal["auto", "none", "weights", "neurons"] = Field(
        "auto", description="auto, none, weights or neurons")
    headroom: _Finite = Field(1.0, ge=1, description="a finite number >= 1")
    calibration: Literal["static", "per-input"] = Field("static",
                                                       description="static or per-input")
    weight_bits: Annotated[int, Field(ge=2, le=64)] | None = Field(
        None, description="an integer in 2..64")


class FftOptions(BaseModel):
    """The radix-4 S-FFT (``dft`` motif ``time-fft``; ``compiler.lowering.dft_fft``)."""

    model_config = _CONFIG
    time_steps: _Steps = Field(256, description="an integer >= 1")
    fft_radices: tuple[Annotated[int, Field(ge=2, le=1 << 16)], ...] | None = Field(
        None, min_length=1, description="a list of integer radices >= 2")
    input_range: _Finite = Field(1.0, gt=0, description="a finite number > 0")


class RateOptions(BaseModel):
    """The rate-coded S-DFT (``dft``/``linear`` motif ``rate``; ``compiler.lowering.dft_rate``)."""

    model_config = _CONFIG
    time_steps: _Steps = Field(2000, description="an integer >= 1")
    input_range: _Finite = Field(1.0, gt=0, description="a finite number > 0")
    headroom: _Finite = Field(1.0, ge=1, description="a finite number >= 1")


class CfarOptions(BaseModel):
    """The time-coded CA-/OS-CFAR (``cfar`` motif ``time``; ``compiler.lowering.cfar``)."""

    model_config = _CONFIG
    time_steps: _Steps = Field(100, description="an integer >= 1")
    cfar_range: _Pair | dict[str, _Pair] | None = Field(
        None, description="a pair (lo, hi) of finite numbers, or a mapping of node id to one")
    cfar_quantiles: tuple[_Quantile, _Quantile] | dict[str, tuple[_Quantile, _Quantile]] | None \
        = Field(None, description="a pair (lo, hi) of quantiles, 0 <= lo <= hi <= 1, or a "
                                  "mapping of node id or CFAR kind to one")
    cfar_ties: Literal["balanced", "exact"] = Field("balanced", description="balanced or exact")
    cfar_steps: _Steps | None = Field(
        None, description="an integer >= 1 (the CFAR's own steps; default time_steps)")


class ResonatorOptions(BaseModel):
    """The resonate-and-fire DFT (``dft`` motif ``resonator``; ``compiler.lowering.resonator``)."""

    model_config = _CONFIG
    stream_bits: Annotated[int, Field(ge=1)] | None = Field(
        None, description="an integer >= 1 (bits of the stream code per input part)")
    resonator_readout: Literal["auto", "time", "log", "graded"] = Field(
        "auto", description="auto, time, log or graded")
    resonator_coef_bits: Annotated[int, Field(ge=2, le=30)] | None = Field(
        None, description="an integer in 2..30 (fraction bits of the rotation coefficients)")
    resonator_decay: _Finite = Field(1.0, gt=0, le=1, description="a number in (0, 1]")
    resonator_drift_max: _Finite | None = Field(None, gt=0, description="a finite number > 0")
    resonator_renorm: Literal["auto", "off"] | Annotated[int, Field(ge=2)] = Field(
        "auto", description="auto, off or an integer >= 2 (steps per renormalised block)")


#: Every motif family's option model (TimeInputOptions: the S-FT's input and read-out).
MOTIF_OPTION_MODELS: tuple[type[BaseModel], ...] = (
    TimeDftOptions, TimeInputOptions, FftOptions, RateOptions, CfarOptions, ResonatorOptions)

#: Model class -> its settings for one compile.
MotifSettings = Mapping[type[BaseModel], BaseModel]
