r"""Which neuron features a population needs, and whether a target's stock neurons have them.

A population's :class:`~compiler.snn.NeuronParams` may use more than a chip's stock
compartment does. Each feature is one test on the parameters against the profile's neuron
fields (``docs/hardware.md``):

=====================  =============================================  ==========================
feature                the population needs it when                   profile field
=====================  =============================================  ==========================
non-leaking current    ``du·4096 < current_decay_offset_lsb``         ``current_decay_offset_lsb``
no membrane memory     ``dv = 1``                                     ``full_voltage_decay``
subtractive reset      it may spike and resets by ``v −= θ``          ``reset`` (``zero``)
reset to a value ≠ 0   it may spike and resets to ``v_reset ≠ 0``     ``reset`` (not
                                                                      ``programmable``)
reset to 0             it may spike and resets to ``v_reset = 0``     ``reset`` (``subtract``)
fire-once              ``reset = "fire_once"`` and it may spike       ``fire_once``
spiking gate           ``spiking_on`` changes between its phases      ``threshold_schedule``
input gate             ``input_on`` changes between its phases        ``input_gate``
resonate-and-fire      its parameters are resonator parameters        ``resonate_and_fire``
=====================  =============================================  ==========================

A bias schedule (a constant bias per phase) is a host write between run segments and is
not a feature; neither is a population that never spikes (its membrane is read).

Examples
--------
>>> from compiler.hardware import load_profile
>>> from compiler.snn import NeuronParams
>>> ramp = NeuronParams(du=0.0, dv=0.0, v_th=5.0, reset="fire_once")
>>> [m.split(" (")[0] for m in missing_features(ramp, load_profile("loihi"))]
['a non-leaking current', 'fire-once']
>>> missing_features(ramp, load_profile("loihi2"))
[]
>>> missing_features(NeuronParams(du=1.0, v_th=1.0, reset="value"), load_profile("loihi"))
[]
"""

from __future__ import annotations

from compiler.snn import DECAY_ONE, NeuronParams
from compiler.snn.resonator import ResonatorParams
from ir.errors import CompileError

__all__ = ["check_population", "missing_features"]


def _switches(params: NeuronParams, field: str) -> bool:
    return len({getattr(ph, field) for ph in params.phases}) > 1


def missing_features(params: NeuronParams, profile) -> list[str]:
    """The features ``params`` needs that ``profile``'s stock neurons lack (see module doc).

    Parameters
    ----------
    params : NeuronParams
        One population's parameters.
    profile : HardwareProfile
        The target.

    Returns
    -------
    list of str
        One phrase per missing feature, naming the profile field (empty: all stock).
    """
    out: list[str] = []
    if isinstance(params, ResonatorParams) and not profile.resonate_and_fire:
        return ["resonate-and-fire neurons (resonate_and_fire: false)"]
    offset = profile.number_format.current_decay_offset_lsb
    if round(params.du * DECAY_ONE) < offset:
        out.append(f"a non-leaking current (du = {params.du:g}; the current decays by at least "
                   f"{offset}/{DECAY_ONE} a step: current_decay_offset_lsb {offset})")
    if params.dv == 1.0 and not profile.full_voltage_decay:
        out.append("a membrane without memory (dv = 1; the decay register stops below 1: "
                   "full_voltage_decay false)")
    may_spike = any(ph.spiking_on for ph in params.phases)
    reset = profile.reset
    if may_spike and params.reset == "subtract" and reset == "zero":
        out.append("subtractive reset (reset: zero; the stock neuron sets v = 0)")
    if may_spike and params.reset == "value" and reset != "programmable":
        if params.v_reset != 0:
            out.append(f"a reset to v = {params.v_reset:g} (reset: {reset})")
        elif reset == "subtract":
            out.append("a reset to 0 (reset: subtract)")
    if may_spike and params.reset == "fire_once" and profile.fire_once == "none":
        out.append("fire-once (fire_once: none)")
    if _switches(params, "spiking_on") and not profile.threshold_schedule:
        out.append("a spiking gate: spiking switched on or off mid-run (threshold_schedule: "
                   "false)")
    if _switches(params, "input_on") and not profile.input_gate:
        out.append("an input gate: the synaptic input cut for a phase (input_gate: false)")
    return out


def check_population(population, profile, *, fix: str) -> None:
    """Refuse a population whose neurons need a feature ``profile`` lacks.

    Parameters
    ----------
    population : Population
        A neuron population (sources are never refused).
    profile : HardwareProfile or None
        The target (``None``: nothing to check).
    fix : str
        The way out, e.g. ``"use target loihi2 or motifs={'f': 'host'}"``.

    Raises
    ------
    CompileError
        One line: the node, motif and population, the missing features, the fix. A
        missing feature is a motif the target lacks (the ``motifs="auto"`` search skips
        it, and may take the host), not a budget (:class:`~ir.errors.BudgetError`: too big
        for the chip).

    Examples
    --------
    >>> from compiler.hardware import load_profile
    >>> from compiler.snn import NeuronParams, Population
    >>> pop = Population(id="f/out", shape={"k": 2}, origin={"node": "f", "motif": "rate"},
    ...                  params=NeuronParams(du=1.0, v_th=1.0, reset="subtract"))
    >>> check_population(pop, load_profile("loihi"), fix="use target loihi2")
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: node 'f' (motif rate, population 'f/out') needs subtractive reset \
(reset: zero; the stock neuron sets v = 0), which the stock neurons of loihi lack; use target loihi2
    """
    if profile is None or population.source:
        return
    missing = missing_features(population.params, profile)
    if missing:
        node, motif = population.origin.get("node", "?"), population.origin.get("motif", "?")
        raise CompileError(f"node {node!r} (motif {motif}, population {population.id!r}) needs "
                          f"{' and '.join(missing)}, which the stock neurons of "
                          f"{profile.name} lack; {fix}", node=node)
