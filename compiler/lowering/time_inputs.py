r"""Measured choices of the time-coded S-FT about its inputs and outputs across frames.

* :func:`input_rounding` — nearest or dithered rounding of a host-encoded input, measured on
  the calibration frames (:func:`repeated_rounding_error`);
* :func:`guard_of` — the guard a read-out layer gets above its calibrated full scale
  (:func:`compiler.lowering.charging.with_guard`).

Both serve a calibration that transfers to frames the calibration set did not contain
(``docs/fourier.md``, "Calibration that transfers to new frames").
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from compiler.calibration import NodeCalibration
from compiler.lowering.charging import guard_steps
from compiler.lowering.context import LoweringContext
from compiler.lowering.options import TimeInputOptions  # its home; re-exported here
from compiler.snn import PartLayout
from compiler.snn.coding import split_values
from ir.errors import BudgetError, CompileError
from ir.ops import DFT, Linear, Output, Sum

__all__ = ["ENCODER_HEADROOM", "TimeInputOptions", "encoder_headroom", "graded_readout",
           "guard_of", "input_rounding", "repeated_rounding_error"]


#: The least headroom of a host encoder's code above the calibrated maximum (6 dB).
ENCODER_HEADROOM = 2.0


def encoder_headroom(rec: NodeCalibration, setting: float | str = "auto") -> float:
    r"""The factor a host encoder's range leaves above a value's calibrated maximum.

    The input code is where a new frame is clipped before any processing, and a frame the
    calibration set did not contain may peak higher (noise peaks over more samples, a
    stronger or closer target).  With the calibration frames' peaks ``P_f`` the factor is

    .. math:: h = \max\bigl(2,\ \max_f P_f / \operatorname{median}_f P_f\bigr)

    (the set's own spread, at least 6 dB); 1 for a range propagated from declared bounds
    (a worst case) and for an input the ``per-input`` policy normalises (its peak is 1).
    It costs the input code ``log₂ h`` bits of resolution.  ``setting`` (option
    ``encoder_headroom``) replaces the rule by a fixed factor, e.g. 1 for a chain run on
    its own calibration data.

    Examples
    --------
    >>> from compiler.calibration import measure
    >>> encoder_headroom(measure("x", np.array([[1.0, 2.0], [3.0, 8.0]]), axes=("s",)))
    2.0
    >>> encoder_headroom(measure("x", np.array([[1.0], [2.0], [10.0]]), axes=("s",)))
    5.0
    """
    if rec.source == "bounds" or rec.normalize_axes:  # a worst case; per slice peak 1
        return 1.0
    if setting != "auto":
        return float(setting)
    peaks = np.asarray(rec.frame_peaks, dtype=np.float64)
    median = float(np.median(peaks)) if peaks.size else 0.0
    spread = float(peaks.max()) / median if median > 0 else 1.0
    return max(ENCODER_HEADROOM, spread)


def input_rounding(ctx: LoweringContext, consumer: str, rec: NodeCalibration,
                   step_size: float, split: PartLayout) -> str:
    """How the host encoder of ``consumer``'s input rounds (option ``input_rounding``).

    ``auto``: measured on the calibration frames of the value (a graph input).
    When a later linear stage transforms along another axis — the Doppler DFT sums
    the range stage's output over chirps — a rounding error that repeats in every
    chirp adds up coherently there: the static part of the signal (leakage, static
    clutter) re-quantised on a grid ``s`` not aligned with the ADC's, with too little
    noise to decorrelate it, gives false zero-Doppler peaks.  ``dither``
    (:func:`compiler.snn.coding.dither_offsets`) makes that error white at the cost
    of twice the rounding noise, so it is chosen where the measured repeated error is
    larger (:func:`repeated_rounding_error` ``> 1``), else ``nearest``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> ctx = SimpleNamespace(settings_of=lambda model: model(input_rounding="nearest"))
    >>> input_rounding(ctx, "f", None, 1.0, "signed")
    'nearest'
    """
    mode = ctx.settings_of(TimeInputOptions).input_rounding
    if mode != "auto":
        return mode
    graph = ctx.graph
    axis = getattr(graph.op(consumer), "axis", None)
    later = {graph.op(n).axis for n in nx.descendants(graph.to_networkx(), consumer)
             if isinstance(graph.op(n), DFT | Linear | Sum)} - {axis}
    names = ctx.types[rec.node].names
    repeat = tuple(1 + names.index(a) for a in sorted(later) if a in names)
    if not repeat or rec.frames is None:
        return "nearest"
    rho = repeated_rounding_error(rec.frames, step_size, repeat, split)
    return "dither" if rho > 1 else "nearest"


def repeated_rounding_error(frames: np.ndarray, step: float, repeat: tuple[int, ...],
                            split: PartLayout) -> float:
    r"""How much larger the repeated part of nearest rounding's error is than dither's.

    With the parts ``p`` of the calibration ``frames`` on the code's grid ``s``, the
    error ``e = s·rint(p/s) − p`` averaged over the ``repeat`` axes (``C`` values
    each: what a later stage sums) has the mean square ``\overline{ē^2}``; dither's
    error is white with power ``s²/6``, ``s²/(6C)`` after the average.  Returns

    .. math:: ρ = \overline{ē^2} \big/ \frac{s^2}{6C}

    (``ρ > 1``: nearest rounding adds more coherent error than dither adds noise).

    Examples
    --------
    A constant over 64 chirps rounds the same way in each; noise of 3 steps does not:

    >>> x = np.full((1, 64, 8), 0.3)
    >>> repeated_rounding_error(x, 1.0, (1,), "signed") > 1
    True
    >>> rng = np.random.default_rng(0)
    >>> repeated_rounding_error(x + 3 * rng.normal(size=x.shape), 1.0, (1,), "signed") < 1
    True
    """
    parts = split_values(np.asarray(frames), split)
    err = step * np.rint(parts / step) - parts
    c = int(np.prod([parts.shape[a] for a in repeat]))
    mean_sq = float(np.mean(np.mean(err, axis=repeat) ** 2))
    return mean_sq / (step * step / (6 * c))


def guard_of(ctx: LoweringContext, node: str, t_steps: int) -> tuple[int, float]:
    """Guard steps and ratio of host-decoded layer ``node`` (:func:`~compiler.lowering.
    charging.with_guard`): option ``charging_guard`` (default :data:`~compiler.lowering.
    charging.GUARD_RATIO`; 1 turns it off).

    Only for a value read out as a graph output (a spectrum the user reads: a clipped
    peak is an error) and measured on calibration inputs (a range propagated from
    declared bounds is a worst case).  A value that goes on to a detector keeps its
    resolution instead: a strong return that saturates is still far above the noise,
    while the guard's threshold range would cost weight bits (the Doppler layer of the
    seed003 chain: 8 → 6 on loihi2, cell sensitivity 0.965 → 0.854).
    """
    ratio = ctx.settings_of(TimeInputOptions).charging_guard
    rec = ctx.calibration.get(node)
    consumers = ctx.graph.consumers_of(node)
    if (ratio <= 1 or rec is None or rec.source == "bounds" or not consumers
            or not all(isinstance(ctx.graph.op(c), Output) for c in consumers)):
        return 0, 1.0
    return guard_steps(t_steps), ratio


def graded_readout(ctx: LoweringContext, node: str, *, host_only: bool,
                   neuron_gains: bool) -> bool:
    r"""Whether layer ``node`` sends its value as one graded spike (option ``output_spikes``).

    A graded spike carries an integer payload (Loihi 2: ``graded_spike_bits`` of the
    profile).  After the silent stage the membrane *is* the layer's value in membrane
    units, ``V = Σ Q (E − t) = (M ẑ)/(q s_in)`` exactly, so a neuron that sends ``V`` as
    its payload replaces the ``T``-step charging stage and its rounding (``± b/2``): the
    read-out is exact up to the weights' and the input code's rounding, one step late
    instead of ``T``.  ``auto`` picks it where the value goes to the host only, the
    target has graded spikes and the layer has no per-neuron gains (their scales act on
    the charging stage); ``graded`` on a target without graded spikes is an error.
    """
    mode = ctx.settings_of(TimeInputOptions).output_spikes
    bits = ctx.target.number_format.graded_spike_bits
    if mode == "time":
        return False
    possible = host_only and not neuron_gains
    if mode == "graded":
        if not bits:
            raise BudgetError(f"node {node!r}: output_spikes='graded' needs a target with graded "
                              f"spikes; {ctx.target.name!r} has binary "
                              "spikes only (graded_spike_bits: null); use output_spikes='time'",
                              node=node)
        if not possible:
            raise CompileError(f"node {node!r}: output_spikes='graded' needs a layer read on "
                               "the host only and without per-neuron gains (stage_gains)",
                               node=node)
        return True
    return bool(bits) and possible
