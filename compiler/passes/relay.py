r"""Relay chains: delays beyond a target's maximum through copies of the source population.

A relay population copies the source (one neuron per source neuron, weight 1, threshold
1, instantaneous current, reset by subtraction — or to 0 on a target whose stock neurons
only reset to 0: its membrane is 0 or 1, so both resets leave 0 — so it re-emits every spike
exactly ``D`` steps later) and the synapse keeps the remaining ``d - D``; a delay of ``d`` needs
``ceil(d / D) - 1`` relay stages (shared by every projection from that source).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from compiler.hardware import HardwareProfile
from compiler.passes.split import describe
from compiler.snn import NeuronParams, Population, SpikingNetwork, StencilProjection
from ir.errors import BudgetError

if TYPE_CHECKING:
    from compiler.passes.quantize import QuantizeRecord

__all__ = ["LongDelays", "MAX_RELAY_STAGES", "relay_long_delays"]

LongDelays = Literal["error", "relay"]

#: Most relay stages one long delay may need (a 6-bit target: delays up to ~64 k steps).
MAX_RELAY_STAGES = 1024

def _relay_population(src: Population, stage: int, profile: HardwareProfile) -> Population:
    reset = "value" if profile.reset == "zero" else "subtract"
    return Population(id=f"{src.id}__relay{stage}", shape=dict(src.shape),
                      params=NeuronParams(du=1.0, dv=0.0, v_th=1.0, reset=reset),
                      origin={**src.origin, "motif": "delay_relay"})


def _relay_link(src: str, relay: Population, first_axis: str, delay: int, origin: dict):
    return StencilProjection(id=f"{relay.id}__in", source=src, target=relay.id,
                             axes=(first_axis,), kernel=np.ones(1), edge=("clip",),
                             delays=np.array([delay]), origin={**origin, "motif": "delay_relay"})


def _split_by_delay(p, limit: int):
    """``(near, far)``: the synapses with delay ≤ limit, and the rest with ``limit`` subtracted."""
    w, d = p.stored_weights(), p.delays
    far = d > limit
    near_w, far_w = np.where(far, 0.0, w), np.where(far, w, 0.0)
    near_d, far_d = np.where(far, 0, d), np.where(far, d - limit, 0)
    near = replace(p.with_weights(near_w), delays=near_d)
    far_p = replace(p.with_weights(far_w), delays=far_d, id=f"{p.id}__far")
    return near, far_p


def relay_long_delays(network: SpikingNetwork, profile: HardwareProfile, long_delays: LongDelays,
                      record: QuantizeRecord | None = None) -> SpikingNetwork:
    """Replace delays beyond ``profile.number_format.max_delay_steps`` by relay chains, or raise.

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
    limit = profile.number_format.max_delay_steps
    if limit is None or all(p.max_delay <= limit for p in network.projections):
        return network
    pops = network.population
    if long_delays != "relay" or limit == 0:
        p = next(p for p in network.projections if p.max_delay > limit)
        tgt = pops[p.target]
        raise BudgetError(
            f"{describe(tgt)}: projection {p.id!r} has a delay of {p.max_delay} steps but "
            f"{profile.name} allows at most {limit} ({profile.number_format.delay_bits} delay "
            "bits); "
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
        if np.any(near.stored_weights() != 0):
            projs.append(near)
        key = (p.source.split("__relay")[0], stage + 1)
        if key not in relays:
            src = pops[key[0]]
            relays[key] = _relay_population(src, stage + 1, profile)
            new_pops.append(relays[key])
            projs.append(_relay_link(p.source, relays[key], src.axes[0], limit, p.origin))
            if record is not None:
                record.relays.append(relays[key].id)
        todo.append((replace(far, source=relays[key].id), stage + 1))
    return replace(network, populations=new_pops, projections=projs)
