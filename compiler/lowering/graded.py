"""Graded read-out of the time-coded S-FT: the membrane sent as one payload.

See ``output_spikes`` in :mod:`compiler.lowering.time_inputs` (when it is chosen) and
``docs/fourier.md`` (figures).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from compiler.lowering.charging import GUARD_MIN_RATIO
from compiler.lowering.context import LoweringContext
from compiler.lowering.layer_weights import coarsen, connect_levels
from compiler.lowering.time_inputs import guard_of
from compiler.lowering.values import SpikeValue
from compiler.snn import N_PARTS, Decoder, NeuronParams, PartLayout, Phase, Population

if TYPE_CHECKING:
    from compiler.lowering.time_code import LayerInput, TimeCode

__all__ = ["graded_layer"]


def graded_layer(ctx: LoweringContext, node: str, code_in: TimeCode, inputs: list[LayerInput],
                 *, shape: dict[str, int], split: PartLayout, full_scale: float, motif: str,
                 gain_axis: str | None, gains: tuple[float, ...], bits: int,
                 whole: bool) -> SpikeValue:
    """The layer of :func:`time_layer` read out as one graded spike per neuron.

    The silent stage as there; then input and spiking stay off and each neuron's
    membrane ``V`` (whole membrane units) is its payload, decoded as ``unit · V`` (``/2``
    for ± parts: ``V⁺ − V⁻ = 2 M ẑ``).  The weights are coarsened until the largest
    calibrated ``|V|`` times the guard (:func:`~compiler.lowering.time_inputs.guard_of`,
    halved down to 8× first) fits the payload and the membrane state.
    """
    fmt = ctx.target.number_format
    width = min(b for b in (fmt.graded_spike_bits, fmt.state_bits, 64) if b)
    limit = float(2 ** (width - 1) - 1)
    wanted = guard_of(ctx, node, 256)[1]  # the ratio: a read-out layer's, else none
    stacked = np.concatenate([i.matrix.ravel() for i in inputs])

    def fit(unit: float) -> tuple[float, tuple[float, float]]:
        v_full, guard = (full_scale or 1.0) / unit, wanted
        while v_full * guard > limit and guard / 2 >= min(GUARD_MIN_RATIO, wanted):
            guard /= 2
        return v_full * guard / limit, (v_full, guard)

    fitted = coarsen(node, inputs, stacked, code_in, bits, whole, fit, memo=ctx.memo)
    levels, rounding, unit, bits = fitted.levels, fitted.rounding, fitted.unit, fitted.bits
    v_full, guard = fitted.fitted
    e_in = code_in.end
    phases = (Phase(start_step=0, spiking_on=False),
              Phase(start_step=e_in, input_on=False, spiking_on=False))
    params = NeuronParams(du=0.0, dv=0.0, v_th=1.0, reset="fire_once", phases=phases)
    builder = ctx.builder()
    pop: Population = builder.population(node, "out", shape, params, motif=motif)
    connect_levels(builder, node, pop.id, inputs, levels, motif)
    charging = {"kind": "graded", "n_steps": 1, "weight_bits": bits, "unit": unit,
                "rounding": rounding, "guard": {"ratio": guard, "steps": 0},
                "payload_bits": width, "v_full": v_full}
    builder.meta.setdefault("charging", {})[node] = charging
    gained = {"gain_axis": gain_axis, "gains": tuple(gains)} if gain_axis else {}
    half = 0.5 if N_PARTS[split] else 1.0
    dec = Decoder(port=node, population=pop.id, kind="membrane", scale=unit * half,
                  combine=split, node=node, **gained)
    return ctx.spike_value(node, pop, dec, (e_in, e_in + 1), kind="graded", end=e_in + 1,
                           split=split, charging=charging)
