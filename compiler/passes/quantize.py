r"""The ``quantize`` pass: weights, thresholds, biases and delays in the target's formats.

Currents into a population add up, so every population ``T`` has **one** state unit
:math:`s_T` (its membrane's least significant bit, in the lowering's units) shared by its
incoming projections and its own parameters.  Each projection ``p`` then stores its
weights in the profile's format (:mod:`compiler.hardware.formats`): a signed mantissa of
``weight_bits`` times ``2^{e_p}``, one exponent per projection (a synapse format),
``0 ≤ e_p ≤ weight_exponent_max``.

* **Exact networks** — every incoming weight and every parameter of ``T`` a whole number
  of some unit ``2^{-j}``, ``j ≤ 8`` (the time-coded motifs lower at the target's width
  with whole biases; the OS-CFAR's ``k + 1/2``): :math:`s_T = 2^{-j}`, nothing is
  rounded.  A whole weight that needs more mantissa bits than one exponent gives is
  **split** into terms of their own exponents (extra projections ``<id>__x1`` …, extra
  stored weights in the record), so it stays exact — unless that adds more than
  :data:`MAX_SPLIT_SHARE` of the stored weights (levels made for another width: rounded).
* **Others** — weights already on the one-scale grid ``max|w| / (2^{b_w-1} - 1)`` keep
  it (levels trained for the width); else :math:`s_T = \min_p \max|w_p| / (2^{b_w-1} - 1)`
  (the finest projection keeps all its mantissa bits), coarsened until the largest fits
  ``2^{e_max}`` and until threshold, reset and biases fit:
  :math:`w' = \mathrm{round}(w / (s_T 2^{e_p}))\,2^{e_p}`,
  :math:`v_{th}' = \max(1, \mathrm{round}(v_{th} / s_T))`.

Thresholds must fit ``NumberFormat.threshold_max`` (times the largest per-neuron
scale) and biases the bias mantissa/exponent; decays are rounded to multiples of
``1/4096``.  The record states, per projection, the unit, the exponent and terms, the
largest and mean absolute error (and relative to its own ``max|w|``), the weights rounded
to zero and the extra synapses of split terms; per population the threshold and bias
errors.  A ``membrane`` decoder reads the state, so its scale is multiplied by its
population's :math:`s_T` (``v' = v / s_T``); spike-time, count and mask decoders are
unit-free.  A threshold that cannot fit raises :class:`~ir.errors.BudgetError` naming the
node, the value and the limit.  Delays beyond ``2**delay_bits - 1`` steps are relayed or
refused (:mod:`compiler.passes.relay`).

Examples
--------
>>> import numpy as np
>>> from compiler.hardware import load_profile
>>> from compiler.snn import MatrixProjection, NeuronParams, Population, SpikingNetwork
>>> net = SpikingNetwork(name="q", n_steps=4, populations=[
...     Population(id="x", shape={"i": 2}, source=True),
...     Population(id="y", shape={"o": 1}, params=NeuronParams(v_th=0.5))],
...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
...                                   produce=("o",), weights=np.array([[1.0], [-0.3]]))])
>>> q, rec = quantize(net, load_profile("loihi"))
>>> q.projection["w"].weights.ravel().tolist(), q.population["y"].params.v_th
([127.0, -38.0], 64.0)
>>> round(rec.projections["w"]["max_abs_error"], 5), rec.projections["w"]["exponent"]
(0.00079, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from compiler.hardware import HardwareProfile, load_profile
from compiler.hardware.formats import bias_value, weight_terms
from compiler.passes.base import CompileContext, Pass
from compiler.passes.relay import MAX_RELAY_STAGES, LongDelays, relay_long_delays
from compiler.passes.split import describe
from compiler.program import CompiledProgram, Segment
from compiler.snn import DECAY_ONE, Decoder, NeuronParams, Population, SpikingNetwork
from ir.errors import BudgetError

__all__ = ["MAX_RELAY_STAGES", "Quantize", "QuantizeRecord", "quantize", "relay_long_delays"]


@dataclass
class QuantizeRecord:
    """Per projection and population: unit, exponents, terms, rounding errors; relays added."""

    profile: str
    projections: dict[str, dict] = field(default_factory=dict)
    populations: dict[str, dict] = field(default_factory=dict)
    relays: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON-able form."""
        return {"profile": self.profile, "projections": self.projections,
                "populations": self.populations, "relays": self.relays}

    @property
    def extra_weights(self) -> int:
        """Stored weights added by split terms (the report counts their synapse instances)."""
        return sum(int(r.get("extra_weights", 0)) for r in self.projections.values())


#: Most extra stored weights (over the unsplit ones) the exact path may add by splitting;
#: beyond it the weights are rounded instead (they were levels for another width).
MAX_SPLIT_SHARE = 0.05
#: Exact units tried: ``2^0 … 2^-EXACT_UNIT_BITS`` (dyadic weights and biases stay exact).
EXACT_UNIT_BITS = 8


def _whole(x: np.ndarray) -> bool:
    return bool(np.all(np.asarray(x) == np.rint(x)))


def _near_whole(x: np.ndarray, tol: float = 1e-4) -> bool:
    return bool(np.all(np.abs(np.asarray(x) - np.rint(x)) <= tol))


def _exact_unit(pop: Population, incoming: list, peak: float,
                profile: HardwareProfile) -> float | None:
    """The largest unit ``2^-j`` in which every weight and parameter is a whole number
    that split terms can hold exactly (None: there is none)."""
    fmt = profile.number_format
    par = pop.params
    values = np.array([par.v_th, par.v_reset, *(ph.bias for ph in par.phases)])
    w_max = (1 << (fmt.weight_bits - 1)) - 1
    reach = w_max * 2.0 ** (fmt.weight_exponent_max + 7 * 3)  # four 8-bit terms
    for j in range(EXACT_UNIT_BITS + 1):
        unit = 2.0 ** -j
        if peak / unit > reach:
            return None
        if _whole(values / unit) and all(_whole(p.stored_weights() / unit) for p in incoming):
            decays_exact = _whole(np.array([par.du, par.dv]) * DECAY_ONE)
            return unit if decays_exact else None
    return None


def _split_share(terms: dict[str, list]) -> float:
    """Stored weights of split terms over the first terms' (0: nothing split)."""
    first = sum(int(np.count_nonzero(t[0].stored_weights())) for t in terms.values())
    extra = sum(int(np.count_nonzero(q.stored_weights())) for t in terms.values() for q in t[1:])
    return extra / first if first else 0.0


def _state_unit(pop: Population, incoming: list, profile: HardwareProfile,
                allow_exact: bool = True) -> tuple[float, bool]:
    """``(s_T, exact)`` for a population (see the module docstring)."""
    fmt = profile.number_format
    w_max = (1 << (fmt.weight_bits - 1)) - 1
    e_top = 2.0 ** fmt.weight_exponent_max
    peaks = [float(np.abs(p.stored_weights()).max(initial=0.0)) for p in incoming]
    peaks = [x for x in peaks if x > 0]
    exact = _exact_unit(pop, incoming, max(peaks, default=0.0), profile) if allow_exact else None
    if exact is not None:
        return exact, True
    par = pop.params
    if peaks:  # weights already on the one-scale grid (levels made for this width): keep it
        grid = max(peaks) / w_max
        if all(_near_whole(p.stored_weights() / grid) for p in incoming) and grid >= _param_unit(
                par, profile):
            return grid, False
    unit = min(peaks) / w_max if peaks else 1.0
    unit = max(unit, max(peaks, default=0.0) / (w_max * e_top))
    return max(unit, _param_unit(par, profile)), False


def _param_unit(par: NeuronParams, profile: HardwareProfile) -> float:
    """The smallest unit at which threshold, reset and biases fit (0: no limit)."""
    limit = profile.number_format.threshold_max
    if limit is None:
        return 0.0
    peak = max([abs(par.v_th), abs(par.v_reset), *(abs(ph.bias) for ph in par.phases)])
    return peak * max(par.scales, default=1.0) / (limit - 0.5)


def _needs_threshold_grid(par: NeuronParams, profile: HardwareProfile) -> bool:
    """Whether ``v_th`` must be a multiple of ``2^threshold_shift`` in state units.

    A non-leaky neuron (``dv = 0``) that never resets to a value can take any whole
    threshold ``θ``: a shared grid threshold ``θ' ≥ θ`` and the initial membrane ``θ' − θ``
    give the same spikes (per-neuron initial state, ``per_neuron_scales``).
    """
    fmt = profile.number_format
    if not fmt.threshold_shift:
        return False
    offset_ok = fmt.per_neuron_scales and par.dv == 0.0 and par.reset != "value"
    return not offset_ok


def _fit(pop: Population, what: str, value: float, profile: HardwareProfile) -> None:
    fmt = profile.number_format
    limit = fmt.threshold_max
    if limit is not None and abs(value) > limit:
        raise BudgetError(
            f"{describe(pop)}: quantized {what} {value:.0f} exceeds the {what} range of "
            f"{profile.name} (limit {limit}: {fmt.threshold_bits}-bit state"
            + (f", {fmt.threshold_mantissa_bits}-bit mantissa << {fmt.threshold_shift}"
               if fmt.threshold_mantissa_bits else "")
            + "); raise the weights relative to the threshold in the lowering, use fewer "
            "time steps, or a target with wider thresholds", node=pop.origin.get("node", pop.id))


def _quantize_params(pop: Population, unit: float, profile: HardwareProfile
                     ) -> tuple[NeuronParams, dict]:
    fmt = profile.number_format
    par = pop.params
    if par.scale_axis is not None and not fmt.per_neuron_scales:
        raise BudgetError(
            f"{describe(pop)}: needs per-neuron threshold/bias scales along "
            f"{par.scale_axis!r}, which {profile.name} does not provide (per_neuron_scales: "
            "false); compile with stage_gains='weights' or 'none'",
            node=pop.origin.get("node", pop.id))
    top = max(par.scales, default=1.0)
    v_th = max(1.0, float(np.rint(par.v_th / unit)))
    v_reset = float(np.rint(par.v_reset / unit))
    if _needs_threshold_grid(par, profile):
        grid = 2.0 ** fmt.threshold_shift  # the unit was divided by it: whole in grid steps
        v_th = max(grid, float(np.rint(par.v_th / (unit * grid)) * grid))
    for what, v in (("threshold", v_th * top), ("reset", v_reset * top)):
        _fit(pop, what, v, profile)
    phases, bias_error = [], 0.0
    for ph in par.phases:
        b = float(np.rint(ph.bias / unit))
        b = bias_value(b, mantissa_bits=fmt.bias_mantissa_bits,
                       exponent_max=fmt.bias_exponent_max)
        bias_error = max(bias_error, abs(b * unit - ph.bias))
        _fit(pop, "bias", b * top, profile)
        phases.append(ph.model_copy(update={"bias": b}))
    new = par.model_copy(update={
        "v_th": v_th, "v_reset": v_reset, "phases": tuple(phases),
        "du": float(np.rint(par.du * DECAY_ONE) / DECAY_ONE),
        "dv": float(np.rint(par.dv * DECAY_ONE) / DECAY_ONE)})
    info = {"scale": unit, "v_th": v_th, "threshold_error": abs(v_th * unit - par.v_th),
            "bias_error": bias_error, "max_neuron_scale": top}
    return new, info


def _rescaled(dec: Decoder, units: dict[str, float]) -> Decoder:
    """A ``membrane`` decoder in the quantized state: ``v' = v / s_T``, so its scale is
    multiplied by the population's unit ``s_T`` (spike times, counts and masks are unit-free).
    """
    unit = units.get(dec.population, 1.0)
    if dec.kind != "membrane" or unit == 1.0:
        return dec
    return dec.model_copy(update={"scale": dec.scale * unit})


def _projection_terms(p, pop: Population, unit: float, exact: bool,
                      profile: HardwareProfile, record: QuantizeRecord) -> list:
    """``p`` in the target's weight format: itself, plus split terms of an exact weight."""
    fmt = profile.number_format
    w = p.stored_weights()
    w_max = (1 << (fmt.weight_bits - 1)) - 1
    terms = weight_terms(w / unit, w_max, fmt.weight_exponent_max, exact=exact)
    q = sum(t for _, t in terms)
    live = w != 0
    err = np.abs(q * unit - w)[live]
    own = float(np.abs(w).max(initial=0.0))
    extra = [int(np.count_nonzero(t)) for _, t in terms[1:]]
    record.projections[p.id] = {
        "scale": unit, "exponent": terms[0][0], "mantissa_bits": fmt.weight_bits,
        "terms": [{"exponent": e, "synapses": int(np.count_nonzero(t))} for e, t in terms],
        "extra_weights": sum(extra), "exact": exact and not err.any(),
        "max_abs_error": float(err.max(initial=0.0)),
        "mean_abs_error": float(err.mean()) if err.size else 0.0,
        "max_rel_error": float(err.max(initial=0.0) / own) if own else 0.0,
        "rounded_to_zero": int((live & (q == 0)).sum())}
    if live.any() and not q[live].any():
        raise BudgetError(
            f"{describe(pop)}: fitting its threshold/bias ({pop.params.v_th:.4g}) into "
            f"{profile.name}'s threshold range needs a unit of {unit:.4g}, at which every "
            f"weight of projection {p.id!r} (max {own:.4g}) rounds to zero; use fewer time "
            "steps or a target with wider thresholds", node=pop.origin.get("node", pop.id))
    out = [p.with_weights(terms[0][1])]
    out += [replace(p.with_weights(t), id=f"{p.id}__x{i}") for i, (_, t) in
            enumerate(terms[1:], start=1) if t.any()]
    return out


def quantize(network: SpikingNetwork, profile: HardwareProfile | str = "unbounded", *,
             long_delays: LongDelays = "error") -> tuple[SpikingNetwork, QuantizeRecord]:
    """Quantize ``network`` to the profile's weight, threshold, bias and delay formats.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    profile : HardwareProfile or str, default "unbounded"
        The target: a profile, or a built-in name or YAML path (loaded);
        ``unbounded`` changes nothing.
    long_delays : {"error", "relay"}
        What to do with a delay beyond the profile's maximum.

    Returns
    -------
    (SpikingNetwork, QuantizeRecord)

    Raises
    ------
    BudgetError
        A delay too long (with ``"error"``), a threshold/bias beyond the target's range,
        or per-neuron scales on a target without them.
    """
    profile = load_profile(profile)
    fmt = profile.number_format
    record = QuantizeRecord(profile=profile.name)
    net = relay_long_delays(network, profile, long_delays, record)
    if fmt.weight_bits is None:
        return net, record
    new_pops, new_projs, units = [], {}, {}
    for pop in net.populations:
        incoming = net.incoming(pop.id)
        if pop.source:
            new_pops.append(pop)
            continue
        unit, exact = _state_unit(pop, incoming, profile)
        terms = {p.id: _projection_terms(p, pop, unit, exact, profile, record) for p in incoming}
        if exact and _split_share(terms) > MAX_SPLIT_SHARE:
            # whole weights, but exactness would cost too many extra synapses (levels
            # trained or chosen for another width): round them in the target's format
            unit, exact = _state_unit(pop, incoming, profile, allow_exact=False)
            terms = {p.id: _projection_terms(p, pop, unit, exact, profile, record)
                     for p in incoming}
        if _needs_threshold_grid(pop.params, profile):
            # thresholds are a mantissa << shift and no per-neuron offset can stand in:
            # the whole population moves up by the shift (weights gain exponent, as a weight
            # exponent of 0 on Loihi lines the weight up with the threshold's shift)
            unit /= 2.0 ** fmt.threshold_shift
            terms = {p.id: _projection_terms(p, pop, unit, exact, profile, record)
                     for p in incoming}
        new_projs.update(terms)
        coarsened = not exact and _param_unit(pop.params, profile) >= unit > 0 and incoming
        params, info = (_quantize_params(pop, unit, profile) if fmt.threshold_max
                        else (pop.params, {"scale": unit}))
        info.update(weights_coarsened_for_threshold=bool(coarsened), exact=exact)
        record.populations[pop.id] = info
        units[pop.id] = unit
        new_pops.append(pop.model_copy(update={"params": params}))
    projections = [q for p in net.projections for q in new_projs.get(p.id, [p])]
    out = replace(net, populations=new_pops, projections=projections,
                  decoders=[_rescaled(d, units) for d in net.decoders])
    out.meta = {**net.meta, "quantized_for": profile.name}
    if fmt.state_bits is not None:  # the simulator counts states beyond it
        out.meta["state_bits"] = fmt.state_bits
    return out, record


@dataclass(frozen=True)
class Quantize(Pass):
    """Quantize every spiking segment's network to the target; record ``records["quantize"]``.

    With ``ctx.memo`` a quantized network equal to one an earlier attempt of the measured
    compile built is that network (:meth:`compiler.memo.CompileMemo.network`).

    Attributes
    ----------
    long_delays : {"relay", "error"}
        What to do with delays beyond the target's maximum (default: relay them,
        so a chain compiles for any target with delays; ``error`` to be told).
    """

    name: ClassVar[str] = "quantize"
    long_delays: LongDelays = "relay"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = ctx.target
        mode = self.long_delays
        records, segments = [], []
        for seg in program.segments:
            if seg.kind == "spiking" and seg.network is not None:
                net, rec = quantize(seg.network, profile, long_delays=mode)
                if ctx.memo is not None:  # an earlier attempt's equal network, reused
                    net = ctx.memo.network(net)
                seg = Segment(kind=seg.kind, inputs=seg.inputs, outputs=seg.outputs,
                              network=net, node=seg.node)
                records.append(rec)
            segments.append(seg)
        program.segments = segments
        program.records.quantization = records
        return program
