r"""The ``split`` pass: cut every neuron population into blocks that each fit one core.

For a population the starting block count is NengoLoihi's rule

.. math:: n = \max\Big(\Big\lceil \tfrac{\text{neurons}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{fan-in lines}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{fan-out lines}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{synapse bits}}{\max}\Big\rceil\Big)

evaluated on the worst block (a fan-in that does not shrink with the block, as a
dense matrix's, makes it grow); the blocks (equal sizes ±1, contiguous in memory
order) are then measured exactly with :func:`compiler.hardware.block_demand`,
``n`` grows until every block fits, and a bisection returns the smallest such
``n`` found.  What cannot fit even one neuron per core, or a network larger than
all cores, raises :class:`~ir.errors.BudgetError` naming the IR node and motif.

Examples
--------
>>> import numpy as np
>>> from compiler.hardware import load_profile
>>> from compiler.snn import MatrixProjection, Population, SpikingNetwork
>>> net = SpikingNetwork(name="t", n_steps=4, populations=[
...     Population(id="x", shape={"i": 8}, source=True),
...     Population(id="y", shape={"o": 3000}, origin={"node": "fc", "motif": "dense"})],
...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
...                                   produce=("o",), weights=np.ones((8, 3000)))])
>>> rec = split(net, load_profile("loihi"))
>>> rec.blocks["y"].sizes.tolist()
[1000, 1000, 1000]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import ceil
from typing import ClassVar

import numpy as np

from compiler.hardware import BUDGETS, Blocks, HardwareProfile, load_profile
from compiler.hardware.demand import Demand, block_demand, stored_synapses, synapse_instances
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from compiler.snn import Population, SpikingNetwork
from ir.errors import BudgetError

__all__ = ["REACH_LIMIT", "Split", "SplitRecord", "split", "describe"]

#: Without a fan-in budget, fan-in lines (and so the spike traffic) are counted only for
#: populations receiving at most this many synapse instances.
REACH_LIMIT = 1 << 27

_BUDGET_TEXT = {
    "neurons": "neurons",
    "input_axons": "input axons (fan-in lines)",
    "output_axons": "output axons (fan-out lines)",
    "synapse_bits": "bits of synaptic memory",
}
_SUGGEST = {
    "neurons": "use more cores or chips (a profile file with a larger 'chips'), or run the "
               "largest stages on the host",
    "input_axons": "reduce the fan-in (a smaller window or a sparser matrix, e.g. the radix-4 "
                   "S-FFT instead of a dense DFT) or use a target with more input axons per core",
    "output_axons": "let each neuron drive fewer target populations, or use a target with more "
                    "output axons per core",
    "synapse_bits": "store fewer or narrower synapses (fewer training cells, a sparser matrix), "
                    "or use a target with more synaptic memory or shared weights",
}


def describe(pop: Population) -> str:
    """How error messages name a population: its IR node and motif when known.

    Examples
    --------
    >>> describe(Population(id="det", shape={"r": 2}, origin={"node": "det", "motif": "os_cfar"}))
    "node 'det' (motif os_cfar, population 'det')"
    >>> describe(Population(id="y", shape={"r": 2}))
    "population 'y'"
    """
    if "node" not in pop.origin:
        return f"population {pop.id!r}"
    return (f"node {pop.origin['node']!r} (motif {pop.origin.get('motif', '?')}, "
            f"population {pop.id!r})")


@dataclass
class SplitRecord:
    """The blocks of every neuron population of one network, with their measured demand.

    Attributes
    ----------
    network : str
        The network's name.
    profile : str
        The profile's name.
    demand : dict of str to Demand
        Per neuron population (in population order): its blocks and per-block amounts.
    """

    network: str
    profile: str
    demand: dict[str, Demand] = field(default_factory=dict)

    @property
    def blocks(self) -> dict[str, Blocks]:
        """The blocks of each neuron population."""
        return {k: d.blocks for k, d in self.demand.items()}

    @property
    def n_blocks(self) -> int:
        """Blocks over all populations."""
        return sum(d.blocks.n_blocks for d in self.demand.values())

    def to_dict(self) -> dict:
        """A JSON-able summary: blocks and the largest block's amounts per population."""
        return {"network": self.network, "profile": self.profile, "populations": {
            k: {"blocks": d.blocks.n_blocks,
                "max_per_block": dict(zip(BUDGETS, d.amounts.max(axis=0).tolist(), strict=True)),
                "stored_synapses": int(d.entries.sum())}
            for k, d in self.demand.items()}}


def _fits(amounts: np.ndarray, limits: np.ndarray) -> tuple[bool, float]:
    ratio = float((amounts / limits).max()) if amounts.size else 0.0
    return ratio <= 1.0, ratio


def _check_totals(network: SpikingNetwork, profile: HardwareProfile, limits: np.ndarray) -> None:
    cores = profile.n_cores
    if cores is None:
        return
    pops = [p for p in network.populations if not p.source]
    need = {
        "neurons": sum(p.size for p in pops),
        "synapse_bits": stored_synapses(network, profile.shared_weights_per_core)
        * profile.bits_per_synapse,
    }
    # the budget that needs the most cores is the one to report
    budget = max(need, key=lambda b: need[b] / limits[BUDGETS.index(b)])
    amount, limit = need[budget], limits[BUDGETS.index(budget)]
    if amount > limit * cores:
        biggest = max(pops, key=lambda p: p.size)
        n = ceil(amount / limit)
        raise BudgetError(
            f"network {network.name!r} needs {amount:,} {_BUDGET_TEXT[budget]} but "
            f"{profile.name} has {int(limit):,} per core x {cores} cores = "
            f"{int(limit * cores):,}: at least {n:,} cores "
            f"({ceil(n / profile.cores_per_chip):,} chips of {profile.cores_per_chip} cores, "
            f"{profile.chips} available); the largest population is {describe(biggest)} with "
            f"{biggest.size:,} neurons; {_SUGGEST[budget]}", node=biggest.origin.get("node"))


def _too_big(pop: Population, profile: HardwareProfile, amounts: np.ndarray,
             limits: np.ndarray) -> BudgetError:
    worst = np.unravel_index(np.argmax(amounts / limits), amounts.shape)
    budget = BUDGETS[worst[1]]
    return BudgetError(
        f"{describe(pop)}: even one neuron per core needs {int(amounts[worst]):,} "
        f"{_BUDGET_TEXT[budget]}, {profile.name} allows {int(limits[worst[1]]):,} per core; "
        f"{_SUGGEST[budget]}", node=pop.origin.get("node", pop.id))


def split_population(network: SpikingNetwork, pop: Population,
                     profile: HardwareProfile) -> Demand:
    """The fewest uniform blocks (found by growth then bisection) whose every block fits a core.

    Raises
    ------
    BudgetError
        If blocks of one neuron still exceed a budget.
    """
    limits = profile.limits()
    pops = network.population
    # fan-in lines are counted when budgeted, or when cheap enough to give the spike traffic
    reach = bool(np.isfinite(limits[1])) or sum(
        synapse_instances(p, pops) for p in network.incoming(pop.id)) <= REACH_LIMIT

    def measure(n: int) -> Demand:
        return block_demand(network, pop.id, Blocks.uniform(pop.id, pop.size, n),
                            bits_per_synapse=profile.bits_per_synapse,
                            shared_weights=profile.shared_weights_per_core, reach=reach)

    n = ceil(pop.size / limits[0]) if np.isfinite(limits[0]) else 1
    bad = 0
    if not profile.shared_weights_per_core and np.isfinite(limits[3]):
        # unshared entries sum to the same total for any split: a lower bound on n
        bits = profile.bits_per_synapse * sum(
            synapse_instances(p, pops) for p in network.incoming(pop.id))
        n = max(n, min(pop.size, ceil(bits / limits[3])))
        bad = n - 1
    attempts = 0
    while True:
        attempts += 1
        d = measure(n)
        ok, ratio = _fits(d.amounts, limits)
        if ok:
            break
        if n == pop.size:
            raise _too_big(pop, profile, d.amounts, limits)
        bad = max(bad, n)
        step = 1 if attempts <= 3 else max(1, n // 8)  # creep first, then grow geometrically
        n = min(pop.size, max(ceil(n * ratio), n + step, bad + 1))
    while n - bad > 1:  # smallest fitting n in (bad, n]
        mid = (bad + n) // 2
        d_mid = measure(mid)
        if _fits(d_mid.amounts, limits)[0]:
            n, d = mid, d_mid
        else:
            bad = mid
    return d


def split(network: SpikingNetwork, profile: HardwareProfile | None = None) -> SplitRecord:
    """Cut every neuron population of ``network`` into blocks that fit one core each.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    profile : HardwareProfile, optional
        The target (``None``: ``unbounded``).

    Returns
    -------
    SplitRecord

    Raises
    ------
    BudgetError
        The network exceeds all cores together, or one neuron exceeds a core.
    """
    profile = load_profile(profile)
    _check_totals(network, profile, profile.limits())
    pops = network.population
    record = SplitRecord(network=network.name, profile=profile.name)
    for pid in network.population_order():
        if not pops[pid].source:
            record.demand[pid] = split_population(network, pops[pid], profile)
    return record


@dataclass(frozen=True)
class Split(Pass):
    """Split every spiking segment's network; record ``records["split"]`` (one per network)."""

    name: ClassVar[str] = "split"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = load_profile(ctx.target)
        records = []
        for net in program.networks:
            ctx.progress(self.name, f"network {net.name!r}")
            records.append(split(net, profile))
        program.records[self.name] = records
        return program
