"""The result of the ``split`` pass: every neuron population's blocks and their demand.

:class:`SplitRecord` holds, per network, the :class:`~compiler.hardware.Demand` of
every neuron population and which stages are time-multiplexed;
:func:`describe` is how error messages name a population.

Examples
--------
>>> from compiler.snn import Population
>>> rec = SplitRecord(network="n", profile="loihi", multiplexed={"rng": 4},
...                   stage_of={"rng/out": "rng", "dop/out": "dop"})
>>> rec.runs("rng/out"), rec.runs("dop/out"), rec.n_blocks
(4, 1, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field

from compiler.hardware import BUDGETS, Blocks
from compiler.hardware.demand import Demand
from compiler.snn import Population

__all__ = ["SplitRecord", "describe"]


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
        For a population of a multiplexed stage the blocks cover one instance
        (``blocks.neurons``), and every neuron of that instance is in exactly one block.
    multiplexed : dict of str to int
        Time-multiplexed stages (IR node) and their repetitions per frame.
    stage_of : dict of str to str
        The stage of each neuron population.
    """

    network: str
    profile: str
    demand: dict[str, Demand] = field(default_factory=dict)
    multiplexed: dict[str, int] = field(default_factory=dict)
    stage_of: dict[str, str] = field(default_factory=dict)

    def runs(self, population: str) -> int:
        """Runs per frame of the placed blocks of ``population`` (``R`` if multiplexed, else 1)."""
        return self.multiplexed.get(self.stage_of.get(population, ""), 1)

    def on_chip(self, source: str, target: str) -> bool:
        """Whether synapses ``source → target`` join placed neurons that run together.

        True when both are placed and either both are spatial or both belong to one
        multiplexed stage; otherwise the source's spikes come from the host or the
        frame buffer of a multiplexed stage.
        """
        if source not in self.demand:
            return False
        mux = self.runs(source) > 1 or self.runs(target) > 1
        return not mux or self.stage_of[source] == self.stage_of[target]

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
        return {"network": self.network, "profile": self.profile,
                "multiplexed": dict(self.multiplexed), "populations": {
                    k: {"blocks": d.blocks.n_blocks, "neurons_placed": d.blocks.n_neurons,
                        "multiplexed": self.runs(k) > 1,
                        "max_per_block": dict(zip(BUDGETS, d.amounts.max(axis=0).tolist(),
                                                  strict=True)),
                        "stored_synapses": int(d.entries.sum())}
                    for k, d in self.demand.items()}}
