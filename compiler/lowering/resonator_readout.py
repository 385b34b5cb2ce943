"""The read-out of the ``resonator`` motif: which code, and the scale of each bin.

After the ``N`` input steps a resonator layer holds every bin's state and reads it out
(:mod:`compiler.lowering.resonator`): in the time-linear code of the S-FT (``time``), as
one graded payload per compartment (``graded``), or on a shared logarithmic schedule
(``log``).  :func:`choose_readout` resolves option ``resonator_readout`` against the target and
the consumers, :func:`readout_scales` gives the time code's bias and per-bin scales, and
:func:`log_readout` the logarithmic schedule.  Everything the target decides comes from its
:class:`~compiler.hardware.number_format.NumberFormat`.

Examples
--------
>>> from types import SimpleNamespace
>>> from compiler.hardware import NO_TARGET, load_profile
>>> payload_fits(SimpleNamespace(target=load_profile("loihi2")))
True
>>> payload_fits(SimpleNamespace(target=NO_TARGET))
'has binary spikes only (graded_spike_bits: null)'
"""

from __future__ import annotations

import numpy as np

from compiler.hardware.formats import bias_value
from compiler.lowering.charging import GUARD_RATIO, ChargingSchedule, log_schedule
from compiler.lowering.context import LoweringContext
from compiler.lowering.options import ResonatorOptions
from compiler.lowering.time_code import headroom_of
from ir.errors import BudgetError, CompileError

__all__ = ["MOTIF", "choose_readout", "host_read", "log_readout", "payload_fits", "readout_scales",
           "whole_bias"]

MOTIF = "resonator"


def host_read(ctx: LoweringContext, node: str) -> bool:
    """Whether every consumer takes the value on the host (a resonator re-streams it)."""
    return all(ctx.motif_for(c) in ("host", MOTIF) for c in ctx.graph.consumers_of(node))


def choose_readout(ctx: LoweringContext, node: str) -> str:
    """Option ``resonator_readout``: ``auto`` is ``graded`` where the target has graded spikes
    and the value goes to the host, ``log`` where it goes to the host without them, else
    ``time`` (a spiking consumer reads the linear code)."""
    readout = ctx.settings_of(ResonatorOptions).resonator_readout
    if readout not in ("auto", "time", "log", "graded"):
        raise CompileError(f"node {node!r}: resonator_readout={readout!r} is not 'auto', "
                           "'time', 'log' or 'graded'", node=node)
    host = host_read(ctx, node)
    if readout in ("graded", "log") and not host:
        raise CompileError(f"node {node!r}: resonator_readout={readout!r} is read by the "
                           "host only; a spiking consumer needs 'time'", node=node)
    payload = payload_fits(ctx)
    if readout == "graded" and payload is not True:
        raise BudgetError(f"node {node!r}: resonator_readout='graded' needs graded spikes "
                          f"that carry the held state; {ctx.target.name!r} {payload}; use "
                          "resonator_readout='log'", node=node)
    if readout == "auto" and host:
        return "graded" if payload is True else "log"
    return "time" if readout == "auto" else readout


def payload_fits(ctx: LoweringContext) -> bool | str:
    """True where a graded spike carries a held state (whose calibrated full scale is about
    ``2^(state_bits − 2)``, :func:`_bits`), else why not (binary spikes, or a payload
    narrower than ``state_bits − 1`` bits)."""
    fmt = ctx.target.number_format
    width = fmt.graded_spike_bits
    if not width:
        return "has binary spikes only (graded_spike_bits: null)"
    state = fmt.state_width
    if width < state - 1:
        return (f"sends {width}-bit payloads, narrower than the {state - 1} bits of its "
                f"{state}-bit state at the calibrated full scale")
    return True


def readout_scales(ctx: LoweringContext, node: str, rec, axis: str, full_state: float,
                    t_out: int, integer: bool) -> tuple[float, np.ndarray | None]:
    """Base bias ``b`` and per-bin scales ``c_k`` of the time read-out (None: one scale).

    Where every consumer is on the host, bin ``k`` charges with ``c_k·b`` so that its own
    calibrated maximum spans the window (the DC bin of real captures is far above the
    rest); spiking consumers read one shared scale.
    """
    per_index = rec.axis_max.get(axis)
    host_only = host_read(ctx, node)
    shared = integer and not ctx.target.number_format.per_neuron_scales
    if not (host_only and per_index) or shared:
        return (whole_bias(ctx, full_state / t_out) if integer else full_state / t_out), None
    part_max = np.asarray(per_index, np.float64) * headroom_of(ctx)
    level = np.maximum(part_max / max(rec.max_part * headroom_of(ctx), 1e-300), 1e-6)
    if integer:  # base bias 2, whole scales: bin k charges by 2·c_k
        c = np.maximum(1.0, np.ceil(level * full_state / (2.0 * t_out)))
        return 2.0, c
    return full_state / t_out, level


def log_readout(ctx: LoweringContext, full_state: float, t_out: int,
                 integer: bool) -> ChargingSchedule:
    r"""The logarithmic time read-out of a host-read resonator (:func:`log_schedule`).

    A constant bias resolves ``full/T``: a bin 48 dB under the calibrated peak (at
    ``T = 256``) decodes to 0, and per-bin scales fitted to the calibration frames clip a
    new scene's target in a bin that held noise there. Here every bin shares one scale
    whose top is :data:`~compiler.lowering.charging.GUARD_RATIO` (24 dB) over the
    calibrated full scale — as far as the state holds — and whose levels are geometric
    down to :data:`~compiler.lowering.charging.LOG_DYNAMIC_RANGE` below it.
    """
    fmt = ctx.target.number_format
    top = full_state * GUARD_RATIO
    state_bits = fmt.state_bits if integer else None
    if state_bits:
        top = min(top, float(2 ** (state_bits - 1) - 1) / (1 + 2 ** (1 - t_out)))
    whole = (fmt.bias_mantissa_bits or True) if integer else False
    return log_schedule(t_out, top, whole=whole)


def whole_bias(ctx: LoweringContext, b: float) -> float:
    """An even whole bias the target can hold, at most ``b`` (at least 2)."""
    fmt = ctx.target.number_format
    b = max(2.0, 2.0 * np.floor(b / 2))
    q = bias_value(b, mantissa_bits=fmt.bias_mantissa_bits, exponent_max=fmt.bias_exponent_max)
    return float(max(2.0, 2.0 * np.floor(q / 2)))
