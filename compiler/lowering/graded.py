"""Graded read-out of the time-coded S-FT: the membrane sent as one payload.

See ``output_spikes`` in :mod:`compiler.lowering.time_inputs` (when it is chosen) and
``docs/fourier.md`` (figures).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from compiler.lowering.charging import GUARD_MIN_RATIO
from compiler.lowering.context import LoweringContext
from compiler.lowering.layer_weights import membrane_unit, round_levels
from compiler.lowering.time_inputs import guard_of
from compiler.lowering.values import SpikeValue
from compiler.snn import N_PARTS, Decoder, NeuronParams, Phase, Population, Split

if TYPE_CHECKING:
    from compiler.lowering.dft_time import LayerInput, TimeCode

__all__ = ["graded_layer"]


def graded_layer(ctx: LoweringContext, node: str, code_in: TimeCode, inputs: list[LayerInput],
                 *, shape: dict[str, int], split: Split, full_scale: float, motif: str,
                 gain_axis: str | None, gains: tuple[float, ...], bits: int,
                 whole: bool) -> SpikeValue:
    """The layer of :func:`time_layer` read out as one graded spike per neuron.

    The silent stage as there; then input and spiking stay off and each neuron's
    membrane ``V`` (whole membrane units) is its payload, decoded as ``unit · V`` (``/2``
    for ± parts: ``V⁺ − V⁻ = 2 M ẑ``).  The weights are coarsened until the largest
    calibrated ``|V|`` times the guard (:func:`~compiler.lowering.time_inputs.guard_of`,
    halved down to 8× first) fits the payload and the membrane state.
    """
    target = ctx.target
    width = min(b for b in (getattr(target, "graded_spike_bits", None),
                            getattr(target, "state_bits", None), 64) if b)
    limit = float(2 ** (width - 1) - 1)
    wanted = guard_of(ctx, node, 256)[1]  # the ratio: a read-out layer's, else none
    stacked = np.concatenate([i.matrix.ravel() for i in inputs])
    peak = float(np.abs(stacked).max(initial=0.0)) or 1.0
    top_level = 2 ** (bits - 1) - 1
    for _ in range(8):  # fewer weight levels until the guarded value fits the payload
        q = peak / top_level
        levels, rounding = np.rint(stacked / q), ["nearest"] * len(inputs)
        if whole:
            levels, rounding = round_levels(inputs, q, max(1, N_PARTS[code_in.split]),
                                             top_level)
        unit = membrane_unit(node, q, code_in)
        v_full = (full_scale or 1.0) / unit
        guard = wanted
        while v_full * guard > limit and guard / 2 >= min(GUARD_MIN_RATIO, wanted):
            guard /= 2
        excess = v_full * guard / limit
        if excess <= 1.0 or top_level == 1:
            break
        top_level = max(1, math.floor(top_level / (excess * 1.01)))
    bits = max(2, math.ceil(math.log2(top_level + 1)) + 1)
    e_in = code_in.end
    phases = (Phase(start_step=0, spiking_on=False),
              Phase(start_step=e_in, input_on=False, spiking_on=False))
    params = NeuronParams(du=0.0, dv=0.0, v_th=1.0, reset="fire_once", phases=phases)
    builder = ctx.builder()
    pop: Population = builder.population(node, "out", shape, params, motif=motif)
    offset = 0
    for i, inp in enumerate(inputs):
        w = levels[offset:offset + inp.matrix.size].reshape(inp.matrix.shape)
        offset += inp.matrix.size
        builder.matrix(node, f"w{i}", inp.source, pop.id, contract=inp.contract,
                       produce=inp.produce, motif=motif, weights=w)
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
