"""Weight levels of a time-coded layer on an integer target, and its membrane unit.

Shared by the time-coded S-FT's charging read-out (:mod:`compiler.lowering.dft_time`) and
its graded read-out (:mod:`compiler.lowering.graded`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from compiler.lowering.context import LoweringContext
from compiler.memo import CompileMemo
from compiler.quantize_weights import rint_feedback, rint_keep_sums
from compiler.snn import N_PARTS
from ir.errors import CompileError

if TYPE_CHECKING:
    from compiler.lowering.builder import NetworkBuilder
    from compiler.lowering.time_code import LayerInput, TimeCode

__all__ = ["Coarsened", "coarsen", "connect_levels", "integer_target", "layer_levels",
           "membrane_unit", "round_levels"]


def integer_target(ctx: LoweringContext) -> bool:
    """Whether the program is quantized for a target with integer weights afterwards (then
    biases are whole and rounding keeps each column's response to a constant input)."""
    return ctx.target.number_format.integer


def membrane_unit(node: str, q: float, code_in: TimeCode) -> float:
    """The layer's membrane unit (value units): the weight step times the input code's."""
    unit = q * code_in.scale
    if not (math.isfinite(unit) and unit > 0):
        raise CompileError(f"node {node!r}: its membrane unit underflows ({q:g} per weight "
                           f"level x {code_in.scale:g} per input step): the values it carries "
                           "are too small for floating point; rescale the chain's weights",
                           node=node)
    return unit


def round_levels(inputs: list[LayerInput], q: float, parts: int, w_max: int,
                 memo: CompileMemo | None = None) -> tuple[np.ndarray, list[str]]:
    """Levels of every input matrix for an integer target, and the rule used per input.

    With the calibrated second moment of the input (``feedback``,
    :func:`~compiler.quantize_weights.rint_feedback`) the rounding error is kept off the
    strong inputs that repeat in the calibration data; otherwise (``keep_sums``,
    :func:`~compiler.quantize_weights.rint_keep_sums`) each column's response to a
    constant input — static returns over chirps or samples — stays exact.  With a
    ``memo`` (:class:`~compiler.memo.CompileMemo`) a rounding already done on equal
    arguments is reused.
    """
    out, rules = [], []
    for inp in inputs:
        m = inp.matrix / q
        h = inp.second_moment
        if h is not None and h.shape == (m.shape[0], m.shape[0]):
            rounded = rint_feedback(m, h, w_max) if memo is None else \
                memo.rint_feedback(m, h, w_max)
            out.append(rounded.ravel())
            rules.append("feedback")
        else:
            # rows are (position, part), parts last; an input with fewer rows than the
            # code has parts (the amb motif's one-part relay) is one part
            per = parts if m.shape[0] % parts == 0 else 1
            grouped = m.reshape(-1, per, m.shape[-1])
            out.append(np.clip(rint_keep_sums(grouped, axis=0), -w_max, w_max).ravel())
            rules.append("keep_sums")
    return np.concatenate(out), rules


def layer_levels(inputs: list[LayerInput], stacked: np.ndarray, q: float, whole: bool,
                 parts: int, w_max: int, memo: CompileMemo | None = None
                 ) -> tuple[np.ndarray, list[str]]:
    """The weight levels of a layer at step ``q``: nearest, or :func:`round_levels` (with
    ``memo``) when the target's weights are integers (``whole``)."""
    if whole:  # integer weights: keep the rounding error off the strong static inputs
        return round_levels(inputs, q, parts, w_max, memo)
    return np.rint(stacked / q), ["nearest"] * len(inputs)


def connect_levels(builder: NetworkBuilder, node: str, target: str,
                   inputs: list[LayerInput], levels: np.ndarray, motif: str) -> None:
    """One matrix projection ``w<i>`` per input into population ``target``, its slice of
    the stacked ``levels`` as weights."""
    offset = 0
    for i, inp in enumerate(inputs):
        w = levels[offset:offset + inp.matrix.size].reshape(inp.matrix.shape)
        offset += inp.matrix.size
        builder.matrix(node, f"w{i}", inp.source, target, contract=inp.contract,
                       produce=inp.produce, motif=motif, weights=w)


@dataclass(frozen=True)
class Coarsened:
    """A layer's weights after :func:`coarsen`: stacked levels, rounding rule per input,
    membrane unit, weight width (bits, sign included) and the fit's own result."""

    levels: np.ndarray
    rounding: list[str]
    unit: float
    bits: int
    fitted: Any


def coarsen(node: str, inputs: list[LayerInput], stacked: np.ndarray, code_in: TimeCode,
            bits: int, whole: bool, fit: Callable[[float], tuple[float, Any]], *,
            memo: CompileMemo | None = None) -> Coarsened:
    """Fewer weight levels until the layer fits its target.

    Starting from ``2**(bits-1) - 1`` levels for the largest weight, ``fit(unit)`` gives
    the *excess* (the largest value the neuron must hold over what the target holds,
    ``<= 1`` fits) and its own result for a membrane unit; the top level is divided by
    the excess (1 % margin) and the levels recomputed, at most 8 times or down to one
    level.  ``memo`` goes to :func:`round_levels`.
    """
    parts = max(1, N_PARTS[code_in.split])
    peak = float(np.abs(stacked).max(initial=0.0)) or 1.0
    top_level = 2 ** (bits - 1) - 1
    for _ in range(8):
        q = peak / top_level
        levels, rounding = layer_levels(inputs, stacked, q, whole, parts, top_level, memo)
        unit = membrane_unit(node, q, code_in)
        excess, fitted = fit(unit)
        if excess <= 1.0 or top_level == 1:
            break
        top_level = max(1, math.floor(top_level / (excess * 1.01)))
    return Coarsened(levels=levels, rounding=rounding, unit=unit, fitted=fitted,
                     bits=max(2, math.ceil(math.log2(top_level + 1)) + 1))
