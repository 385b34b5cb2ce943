r"""Time-linear codes: one spike per part value, and the sources that carry them.

A *time-linear code* carries non-negative part values ``z`` by one spike each:
``z = s·(E − t)`` for a spike at step ``t < E`` (no spike: ``z = 0``), with the
code's *end* ``E`` and *scale* ``s``.  Signed and complex values use ± parts
(``signed``: ``(x⁺, x⁻)``; ``re_im_signed``: ``(Re⁺, Re⁻, Im⁺, Im⁻)``), so no value
ever needs an offset.  The encoder of a host value ``x`` uses
``LatencyCode(t_max=T, x_min=0, x_max=X)``: ``t = T − rint(z·T/X)``, i.e. ``E = T``,
``s = X/T`` (``X`` from the calibrate pass: ``max_part · headroom``, or 1 for
``per-input``, whose encoder normalises each slice).

:func:`time_source` gives a population carrying a value in such a code: the
spikes of a time-linear value already in the network, or a host encoder with
the calibrated range.  The layers that read and produce these codes are in
:mod:`compiler.lowering.dft_time`, which re-exports every name here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from compiler.calibration import NodeCalibration
from compiler.lowering.context import LoweringContext
from compiler.lowering.options import TimeDftOptions
from compiler.lowering.time_inputs import TimeInputOptions, encoder_headroom, input_rounding
from compiler.lowering.values import SpikeValue, Value
from compiler.snn import N_PARTS, PART_AXIS, Encoder, LatencyCode, PartLayout
from ir.errors import CompileError

__all__ = ["DEFAULT_TIME_STEPS", "TIME_LINEAR", "LayerInput", "TimeCode", "calibration_of",
           "headroom_of", "time_source", "time_steps"]

#: Charging (and encoding) window ``T`` when the ``time_steps`` option is not given.
DEFAULT_TIME_STEPS = TimeDftOptions().time_steps  # declared in compiler.lowering.options
#: The ``kind`` of a time-linear ``SpikeValue.code``.
TIME_LINEAR = "time-linear"


@dataclass(frozen=True)
class TimeCode:
    """A time-linear code: part value ``scale·(end − t)`` for a spike at ``t``.

    With ``gain_axis``, the part at index ``i`` of that axis carries
    ``gains[i]`` times the value (see the module docstring).

    Examples
    --------
    >>> TimeCode(end=8, scale=0.5, split="signed").as_code()
    {'kind': 'time-linear', 'end': 8, 'scale': 0.5, 'split': 'signed'}
    >>> TimeCode(8, 0.5, "none", gain_axis="range", gains=(1.0, 2.0)).as_code()["gains"]
    [1.0, 2.0]
    """

    end: int
    scale: float
    split: PartLayout
    gain_axis: str | None = None
    gains: tuple[float, ...] = ()

    def as_code(self) -> dict:
        """The JSON-able ``SpikeValue.code``."""
        code = {"kind": TIME_LINEAR, "end": self.end, "scale": self.scale, "split": self.split}
        if self.gain_axis is not None:
            code.update(gain_axis=self.gain_axis, gains=list(self.gains))
        return code


@dataclass(frozen=True)
class LayerInput:
    """One projection into a time layer: ``source`` population, real matrix, axes."""

    source: str
    matrix: np.ndarray
    contract: tuple[str, ...]
    produce: tuple[str, ...]
    second_moment: np.ndarray | None = None  # E[v vᵀ] of the rows' inputs (weight rounding)


def time_steps(ctx: LoweringContext) -> int:
    """The time window ``T`` (option ``time_steps``); at least 2."""
    t = ctx.settings_of(TimeDftOptions).time_steps
    if t < 2:
        raise CompileError(f"time_steps={t} is too short for a time code; use >= 2 (256 typical)")
    return t


def calibration_of(ctx: LoweringContext, node: str, consumer: str) -> NodeCalibration:
    """The calibrate pass's record of ``node`` (raises a clear error without one)."""
    rec = ctx.calibration.get(node)
    if rec is None:
        raise CompileError(f"node {consumer!r}: time-coded motifs need the range of {node!r}, "
                           "which was not calibrated; run the 'calibrate' pass before 'lower' "
                           "and give calibration_inputs={input: array} or "
                           "input_bounds={input: max |value|} (or calibration='per-input')",
                           node=consumer)
    return rec


def headroom_of(ctx: LoweringContext) -> float:
    """The calibration headroom (option ``headroom``, default 1)."""
    return ctx.settings_of(TimeDftOptions).headroom


def time_source(ctx: LoweringContext, consumer: str, value: Value, *, motif: str,
                gains_ok: bool = False) -> tuple[str, TimeCode]:
    """A population carrying ``value`` in a time-linear code, and that code.

    Spikes of a time-linear value in the open network are read directly (if
    they carry stage gains, only by a consumer that handles them,
    ``gains_ok``); anything else is encoded from the host (a visible boundary)
    with the calibrated range, split into ± parts.
    """
    if (isinstance(value, SpikeValue) and value.code.get("kind") == TIME_LINEAR
            and value.network == ctx.network_index and (gains_ok or not value.code.get("gains"))):
        c = value.code
        return value.population, TimeCode(int(c["end"]), float(c["scale"]), c["split"],
                                          c.get("gain_axis"), tuple(c.get("gains", ())))
    host = ctx.to_host(value)
    rec = calibration_of(ctx, host.node, consumer)
    t = time_steps(ctx)
    setting = ctx.settings_of(TimeInputOptions).encoder_headroom
    full = rec.max_part * headroom_of(ctx) * encoder_headroom(rec, setting) or 1.0
    split: PartLayout = "re_im_signed" if host.type.complex else "signed"
    builder = ctx.builder()
    if builder.has_encoder(host.node):
        raise CompileError(f"node {consumer!r}: value {host.node!r} is already encoded in this "
                           "network by another consumer; give it one motif", node=consumer)
    shape = {**host.type.axes, PART_AXIS: N_PARTS[split]}
    pop = builder.population(consumer, "in", shape, motif=motif, source=True)
    builder.encoder(Encoder(port=host.node, population=pop.id, split=split, node=host.node,
                            code=LatencyCode(t_min=0, t_max=t, x_min=0.0, x_max=full,
                                             rounding=input_rounding(ctx, consumer, rec,
                                                                     full / t, split)),
                            normalize_axes=rec.normalize_axes))
    builder.meta["calibration"] = ctx.settings_of(TimeDftOptions).calibration
    return pop.id, TimeCode(end=t, scale=full / t, split=split)
