"""Weight levels of a time-coded layer on an integer target, and its membrane unit.

Shared by the time-coded S-FT's charging read-out (:mod:`compiler.lowering.dft_time`) and
its graded read-out (:mod:`compiler.lowering.graded`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from compiler.lowering.context import LoweringContext
from compiler.quantize_weights import rint_feedback, rint_keep_sums
from ir.errors import CompileError

if TYPE_CHECKING:
    from compiler.lowering.dft_time import LayerInput, TimeCode

__all__ = ["integer_target", "membrane_unit", "round_levels"]


def integer_target(ctx: LoweringContext) -> bool:
    """Whether the program is quantized for a target with integer weights afterwards (then
    biases are whole and rounding keeps each column's response to a constant input)."""
    return getattr(ctx.target, "weight_bits", None) is not None


def membrane_unit(node: str, q: float, code_in: TimeCode) -> float:
    """The layer's membrane unit (value units): the weight step times the input code's."""
    unit = q * code_in.scale
    if not (math.isfinite(unit) and unit > 0):
        raise CompileError(f"node {node!r}: its membrane unit underflows ({q:g} per weight "
                           f"level x {code_in.scale:g} per input step): the values it carries "
                           "are too small for floating point; rescale the chain's weights",
                           node=node)
    return unit


def round_levels(inputs: list[LayerInput], q: float, parts: int, w_max: int
                  ) -> tuple[np.ndarray, list[str]]:
    """Levels of every input matrix for an integer target, and the rule used per input.

    With the calibrated second moment of the input (``feedback``,
    :func:`~compiler.quantize_weights.rint_feedback`) the rounding error is kept off the
    strong inputs that repeat in the calibration data; otherwise (``keep_sums``,
    :func:`~compiler.quantize_weights.rint_keep_sums`) each column's response to a
    constant input — static returns over chirps or samples — stays exact.
    """
    out, rules = [], []
    for inp in inputs:
        m = inp.matrix / q
        h = inp.second_moment
        if h is not None and h.shape == (m.shape[0], m.shape[0]):
            out.append(rint_feedback(m, h, w_max).ravel())
            rules.append("feedback")
        else:
            grouped = m.reshape(-1, parts, m.shape[-1])
            out.append(np.clip(rint_keep_sums(grouped, axis=0), -w_max, w_max).ravel())
            rules.append("keep_sums")
    return np.concatenate(out), rules
