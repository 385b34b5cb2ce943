r"""The ``quantize`` pass: weights, thresholds and delays to the target's integer widths.

Currents into a population add up, so every population ``T`` gets **one** scale
:math:`s_T` shared by its incoming projections and its own parameters:

.. math:: s_T = \frac{\max_{p \to T} \max |w|}{2^{b_w - 1} - 1}, \qquad
          w' = \mathrm{round}(w / s_T), \quad v_{th}' = \max(1, \mathrm{round}(v_{th} / s_T)),

biases and ``v_reset`` likewise, decays rounded to multiples of ``1/4096``.  The
network keeps its meaning in integer units (the simulator's ``int64`` arithmetic
runs it); the record states, per projection, the largest and mean absolute
error :math:`|w' s_T - w|` (and relative to :math:`\max|w|`) and how many weights
rounded to zero, and per population the threshold error.  A threshold, bias or
reset that would need more than ``threshold_bits`` coarsens the population's scale
(its weights get fewer levels; ``weights_coarsened_for_threshold`` in the record);
one that still cannot fit raises :class:`~ir.errors.BudgetError`.

Delays beyond ``D = 2**delay_bits - 1`` steps either raise ``BudgetError``
(``long_delays="error"``) or go through **relay chains** (``"relay"``): a relay
population copies the source (one neuron per source neuron, weight 1, threshold
1, instantaneous current, reset by subtraction, so it re-emits every spike
exactly ``D`` steps later) and the synapse keeps the remaining ``d - D``.

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
>>> round(rec.projections["w"]["max_abs_error"], 5)
0.00079
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import ClassVar, Literal

import numpy as np

from compiler.hardware import HardwareProfile, load_profile
from compiler.passes.base import CompileContext, Pass
from compiler.passes.split import describe
from compiler.program import CompiledProgram, Segment
from compiler.snn import (
    DECAY_ONE,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import BudgetError

__all__ = ["Quantize", "QuantizeRecord", "quantize", "relay_long_delays"]

LongDelays = Literal["error", "relay"]


@dataclass
class QuantizeRecord:
    """Per projection and population: the scale and the rounding errors; the relays added."""

    profile: str
    projections: dict[str, dict] = field(default_factory=dict)
    populations: dict[str, dict] = field(default_factory=dict)
    relays: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON-able form."""
        return {"profile": self.profile, "projections": self.projections,
                "populations": self.populations, "relays": self.relays}


def _weights(p) -> np.ndarray:
    if isinstance(p, StencilProjection):
        return p.kernel
    return p.weights if p.weights is not None else p.values


def _with_weights(p, w: np.ndarray):
    if isinstance(p, StencilProjection):
        return replace(p, kernel=w)
    return replace(p, weights=w) if p.weights is not None else replace(p, values=w)


def _fit(pop: Population, what: str, value: float, limit: int, profile) -> None:
    if abs(value) > limit:
        raise BudgetError(
            f"{describe(pop)}: quantized {what} {value:.0f} needs more than the "
            f"{profile.threshold_bits} threshold bits of {profile.name} (limit {limit}); "
            "raise the weights relative to the threshold in the lowering, or use a target "
            "with wider thresholds", node=pop.origin.get("node", pop.id))


def _state_scale(par: NeuronParams, profile) -> float:
    """The smallest scale at which threshold, reset and biases fit ``threshold_bits``.

    When the weights' own scale is finer than this, the weights are coarsened
    (fewer effective weight levels) rather than the compilation refused; the
    record says so and the rounding errors show the cost.
    """
    if not profile.threshold_bits:
        return 0.0
    limit = (1 << (profile.threshold_bits - 1)) - 1
    peak = max([abs(par.v_th), abs(par.v_reset), *(abs(ph.bias) for ph in par.phases)])
    return peak / (limit - 0.5)


def _quantize_params(pop: Population, scale: float, profile) -> tuple[NeuronParams, dict]:
    par = pop.params
    limit = (1 << (profile.threshold_bits - 1)) - 1
    v_th = max(1.0, float(np.rint(par.v_th / scale)))
    v_reset = float(np.rint(par.v_reset / scale))
    for what, v in (("threshold", v_th), ("reset", v_reset)):
        _fit(pop, what, v, limit, profile)
    phases = []
    for ph in par.phases:
        b = float(np.rint(ph.bias / scale))
        _fit(pop, "bias", b, limit, profile)
        phases.append(ph.model_copy(update={"bias": b}))
    new = par.model_copy(update={
        "v_th": v_th, "v_reset": v_reset, "phases": tuple(phases),
        "du": float(np.rint(par.du * DECAY_ONE) / DECAY_ONE),
        "dv": float(np.rint(par.dv * DECAY_ONE) / DECAY_ONE)})
    info = {"scale": scale, "v_th": v_th, "threshold_error": abs(v_th * scale - par.v_th)}
    return new, info


def quantize(network: SpikingNetwork, profile: HardwareProfile | None = None, *,
             long_delays: LongDelays = "error") -> tuple[SpikingNetwork, QuantizeRecord]:
    """Quantize ``network`` to the profile's weight, threshold and delay widths.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    profile : HardwareProfile, optional
        The target (``None``: ``unbounded``, which changes nothing).
    long_delays : {"error", "relay"}
        What to do with a delay beyond the profile's maximum.

    Returns
    -------
    (SpikingNetwork, QuantizeRecord)

    Raises
    ------
    BudgetError
        A delay too long (with ``"error"``), or a threshold/bias beyond the threshold bits.
    """
    profile = load_profile(profile)
    record = QuantizeRecord(profile=profile.name)
    net = relay_long_delays(network, profile, long_delays, record)
    if profile.weight_bits is None:
        return net, record
    w_max = (1 << (profile.weight_bits - 1)) - 1
    new_pops, new_projs = [], {}
    for pop in net.populations:
        incoming = net.incoming(pop.id)
        if pop.source:
            new_pops.append(pop)
            continue
        peak = max((float(np.abs(_weights(p)).max(initial=0.0)) for p in incoming), default=0.0)
        scale = peak / w_max if peak > 0 else 1.0
        state_scale = _state_scale(pop.params, profile)
        coarsened = state_scale > scale
        scale = max(scale, state_scale)  # thresholds and biases must fit their bits too
        params, info = _quantize_params(pop, scale, profile) if profile.threshold_bits else (
            pop.params, {"scale": scale})
        info["weights_coarsened_for_threshold"] = coarsened
        record.populations[pop.id] = info
        new_pops.append(pop.model_copy(update={"params": params}))
        for p in incoming:
            w = _weights(p)
            q = np.rint(w / scale)
            live = w != 0
            err = np.abs(q * scale - w)[live]
            own = float(np.abs(w).max(initial=0.0))
            record.projections[p.id] = {
                "scale": scale, "max_abs_error": float(err.max(initial=0.0)),
                "mean_abs_error": float(err.mean()) if err.size else 0.0,
                "max_rel_error": float(err.max(initial=0.0) / own) if own else 0.0,
                "rounded_to_zero": int((live & (q == 0)).sum())}
            if live.any() and not q[live].any():
                raise BudgetError(
                    f"{describe(pop)}: fitting its threshold/bias ({pop.params.v_th:.4g}) into "
                    f"the {profile.threshold_bits} threshold bits of {profile.name} needs a "
                    f"scale of {scale:.4g}, at which every weight of projection {p.id!r} "
                    f"(max {own:.4g}) rounds to zero; use fewer time steps or a target with "
                    "wider thresholds", node=pop.origin.get("node", pop.id))
            new_projs[p.id] = _with_weights(p, q)
    out = replace(net, populations=new_pops,
                  projections=[new_projs.get(p.id, p) for p in net.projections])
    out.meta = {**net.meta, "quantized_for": profile.name}
    return out, record


# --------------------------------------------------------------------------- delays
#: Most relay stages one long delay may need (a 6-bit target: delays up to ~64 k steps).
MAX_RELAY_STAGES = 1024

def _relay_population(src: Population, stage: int) -> Population:
    return Population(id=f"{src.id}__relay{stage}", shape=dict(src.shape),
                      params=NeuronParams(du=1.0, dv=0.0, v_th=1.0, reset="subtract"),
                      origin={**src.origin, "motif": "delay_relay"})


def _relay_link(src: str, relay: Population, first_axis: str, delay: int, origin: dict):
    return StencilProjection(id=f"{relay.id}__in", source=src, target=relay.id,
                             axes=(first_axis,), kernel=np.ones(1), edge=("clip",),
                             delays=np.array([delay]), origin={**origin, "motif": "delay_relay"})


def _split_by_delay(p, limit: int):
    """``(near, far)``: the synapses with delay ≤ limit, and the rest with ``limit`` subtracted."""
    w, d = _weights(p), p.delays
    far = d > limit
    near_w, far_w = np.where(far, 0.0, w), np.where(far, w, 0.0)
    near_d, far_d = np.where(far, 0, d), np.where(far, d - limit, 0)
    near = replace(_with_weights(p, near_w), delays=near_d)
    far_p = replace(_with_weights(p, far_w), delays=far_d, id=f"{p.id}__far")
    return near, far_p


def relay_long_delays(network: SpikingNetwork, profile: HardwareProfile, long_delays: LongDelays,
                      record: QuantizeRecord | None = None) -> SpikingNetwork:
    """Replace delays beyond ``profile.max_delay_steps`` by relay chains, or raise.

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.hardware import HardwareProfile
    >>> from compiler.snn import MatrixProjection, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="d", n_steps=12, populations=[
    ...     Population(id="x", shape={"i": 1}, source=True), Population(id="y", shape={"o": 1})],
    ...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
    ...                  produce=("o",), weights=np.ones((1, 1)), delays=np.array([[7]]))])
    >>> out = relay_long_delays(net, HardwareProfile(name="c", delay_bits=2), "relay")
    >>> [p.id for p in out.populations], [p.max_delay for p in out.projections]
    (['x', 'y', 'x__relay1', 'x__relay2'], [3, 3, 1])
    """
    limit = profile.max_delay_steps
    if limit is None or all(p.max_delay <= limit for p in network.projections):
        return network
    pops = network.population
    if long_delays != "relay" or limit == 0:
        p = next(p for p in network.projections if p.max_delay > limit)
        tgt = pops[p.target]
        raise BudgetError(
            f"{describe(tgt)}: projection {p.id!r} has a delay of {p.max_delay} steps but "
            f"{profile.name} allows at most {limit} ({profile.delay_bits} delay bits); "
            + ("compile with long_delays='relay' to insert relay neurons, or use fewer time "
               "steps" if limit else "a target without delays cannot relay them; use a target "
               "with delay bits"),
            node=tgt.origin.get("node", p.id))
    deepest = max(network.projections, key=lambda p: p.max_delay)
    stages = -(-deepest.max_delay // limit) - 1
    if stages > MAX_RELAY_STAGES:  # each stage is a loop turn and a population: refuse early
        tgt = pops[deepest.target]
        raise BudgetError(
            f"{describe(tgt)}: projection {deepest.id!r} has a delay of {deepest.max_delay} "
            f"steps, which needs {stages} relay stages of at most {limit} steps (over the "
            f"limit of {MAX_RELAY_STAGES}); use fewer time steps or a target with more delay "
            "bits", node=tgt.origin.get("node", deepest.id))
    new_pops = list(network.populations)
    projs: list = []
    relays: dict[tuple[str, int], Population] = {}
    todo = [(p, 0) for p in network.projections]
    while todo:
        p, stage = todo.pop(0)
        if p.max_delay <= limit:
            projs.append(p)
            continue
        near, far = _split_by_delay(p, limit)
        if np.any(_weights(near) != 0):
            projs.append(near)
        key = (p.source.split("__relay")[0], stage + 1)
        if key not in relays:
            src = pops[key[0]]
            relays[key] = _relay_population(src, stage + 1)
            new_pops.append(relays[key])
            projs.append(_relay_link(p.source, relays[key], src.axes[0], limit, p.origin))
            if record is not None:
                record.relays.append(relays[key].id)
        todo.append((replace(far, source=relays[key].id), stage + 1))
    return replace(network, populations=new_pops, projections=projs)


@dataclass(frozen=True)
class Quantize(Pass):
    """Quantize every spiking segment's network to the target; record ``records["quantize"]``.

    Attributes
    ----------
    long_delays : {"relay", "error"}
        What to do with delays beyond the target's maximum (default: relay them,
        so a chain compiles for any target with delays; ``error`` to be told).
    """

    name: ClassVar[str] = "quantize"
    long_delays: LongDelays = "relay"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = load_profile(ctx.target)
        mode = ctx.options.get("long_delays", self.long_delays)
        records, segments = [], []
        for seg in program.segments:
            if seg.kind == "spiking" and seg.network is not None:
                net, rec = quantize(seg.network, profile, long_delays=mode)
                seg = Segment(kind=seg.kind, inputs=seg.inputs, outputs=seg.outputs,
                              network=net, node=seg.node)
                records.append(rec)
            segments.append(seg)
        program.segments = segments
        program.records[self.name] = records
        return program
