r"""Spiking magnitude motifs on time-linear ± parts: ``l1`` and ``amb`` (α-max-β-min).

The S-FT delivers a complex value as four non-negative parts
``(Re⁺, Re⁻, Im⁺, Im⁻)`` in one time-linear code (:mod:`compiler.lowering.dft_time`);
at most one of each ± pair spikes, so ``|Re| = Re⁺ + Re⁻`` and ``|Im| = Im⁺ + Im⁻``.

``l1``
    ``|Re| + |Im|``: one two-stage ramp layer with weight 1 from all four parts.
    Against the true modulus ``|z|``: ``1 ≤ l1/|z| ≤ √2`` (+41 % at 45°).
``amb``
    ``α·max(|Re|, |Im|) + β·min(|Re|, |Im|) = β(|Re| + |Im|) + (α − β)·max``.
    The max is read off the earliest spike: a relay neuron per bin (instant
    current, ``v_th = 1``, fire-once) fires at the first part spike, which in a
    time code *is* the largest part — and it spikes in the same code.  The output
    ramp layer sums the parts (weight β) and the relay (weight α − β).  With
    ``α = 123/128``, ``β = 51/128`` (the best pair on a 1/128 grid, near the minimax
    pair 0.9604, 0.3978) the ratio to ``|z|`` stays in ``[α, √(α²+β²)] = [0.9609, 1.0403]``.
``host``
    Decode, ``np.abs`` (or the op's kind) on the host, re-encode downstream — a
    reported boundary.

The output (one neuron per bin, no ``part`` axis) uses the charging schedules of
:mod:`compiler.lowering.charging`; both motifs apply to ``kind: l2`` or ``l1``
magnitude nodes (``square`` needs the host) and their approximation error is
stated above and measured in ``docs/fourier.md``.

Examples
--------
>>> import numpy as np
>>> z = np.array([3.0 + 4.0j, 1.0 + 0.0j])
>>> amb(z).tolist(), l1(z).tolist()
([5.0390625, 0.9609375], [7.0, 1.0])
"""

from __future__ import annotations

import numpy as np

from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_time import time_layer
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.time_code import LayerInput, calibration_of, headroom_of, time_source
from compiler.lowering.values import Value
from compiler.snn import NeuronParams
from ir.errors import CompileError
from ir.ops import Magnitude, Op

__all__ = ["ALPHA", "BETA", "amb", "l1", "register_magnitude"]

#: α-max-β-min coefficients (dyadic).
ALPHA, BETA = 123 / 128, 51 / 128


def l1(z: np.ndarray) -> np.ndarray:
    """``|Re z| + |Im z|`` (what the ``l1`` motif computes)."""
    return np.abs(np.real(z)) + np.abs(np.imag(z))


def amb(z: np.ndarray) -> np.ndarray:
    """``α·max(|Re|, |Im|) + β·min(|Re|, |Im|)`` (what the ``amb`` motif computes)."""
    a, b = np.abs(np.real(z)), np.abs(np.imag(z))
    return ALPHA * np.maximum(a, b) + BETA * np.minimum(a, b)


def _source(ctx: LoweringContext, node: str, op: Op, inputs: list[Value], motif: str):
    (x,) = inputs
    if op.kind == "square":
        raise CompileError(f"node {node!r} (magnitude kind 'square'): motif {motif!r} computes "
                           "an amplitude, not a power; use motif 'host' or kind 'l2'/'l1'",
                           node=node)
    if not x.type.complex:
        raise CompileError(f"node {node!r}: motif {motif!r} needs a complex input, "
                           f"{x.node!r} is real; use motif 'host'", node=node)
    source, code = time_source(ctx, node, x, motif=motif)
    return source, code, calibration_of(ctx, x.node, node)


def _samples(ctx: LoweringContext, node: str) -> tuple[float, ...]:
    """Calibration quantiles of the node's own (true) magnitude, for the charging schedule."""
    rec = ctx.calibration.get(node)
    return tuple(rec.abs_quantiles) if rec is not None else ()


def lower_l1(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> Value:
    """Rule of motif ``l1``: ``|Re| + |Im|`` from the four ± parts."""
    source, code, rec = _source(ctx, node, op, inputs, "l1")
    layer = LayerInput(source, np.ones((4, 1)), ("part",), ())
    return time_layer(ctx, node, code, [layer], shape=dict(ctx.types[node].axes), split="none",
                      full_scale=rec.max_l1 * headroom_of(ctx), samples=_samples(ctx, node),
                      motif="l1")


def lower_amb(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> Value:
    """Rule of motif ``amb``: α-max-β-min with the max from the earliest part spike."""
    source, code, rec = _source(ctx, node, op, inputs, "amb")
    shape = dict(ctx.types[node].axes)
    builder = ctx.builder()
    relay_params = NeuronParams(du=1.0, dv=1.0, v_th=1.0, reset="fire_once")
    relay = builder.population(node, "max", {**shape, "part": 1}, relay_params, motif="amb")
    builder.matrix(node, "first", source, relay.id, contract=("part",), produce=("part",),
                   motif="amb", weights=np.ones((4, 1)))
    layers = [LayerInput(source, np.full((4, 1), BETA), ("part",), ()),
              LayerInput(relay.id, np.full((1, 1), ALPHA - BETA), ("part",), ())]
    full = rec.max_abs * float(np.hypot(ALPHA, BETA)) * headroom_of(ctx)
    return time_layer(ctx, node, code, layers, shape=shape, split="none", full_scale=full,
                      samples=_samples(ctx, node), motif="amb")


def register_magnitude(registry: LoweringRegistry) -> None:
    """Register motifs ``l1`` and ``amb`` for ``magnitude`` (the default stays ``host``)."""
    registry.register(Magnitude, "l1", lower_l1)
    registry.register(Magnitude, "amb", lower_amb)
