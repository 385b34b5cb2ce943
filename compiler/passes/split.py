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

**Repetitions** (option ``repetitions``): a multiplexable stage
(:mod:`compiler.hardware.repetition`) with :math:`R` repetitions is either
unrolled (``spatial``: all :math:`R` copies resident) or time-multiplexed (one
instance is split and placed, and run :math:`R` times per frame).  ``temporal``
multiplexes every multiplexable stage; ``auto`` (default) tries the spatial
program first, then multiplexes stages largest first (the most cores a stage
needs by its neurons and unshared synapse bits) until the program fits.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from math import ceil
from typing import ClassVar

import numpy as np

from compiler.hardware import BUDGETS, Blocks, HardwareProfile, load_profile
from compiler.hardware.demand import Demand, block_demand, synapse_instances
from compiler.hardware.repetition import Stage, instance_neurons, stage_key, stages
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from compiler.snn import Population, SpikingNetwork
from ir.errors import BudgetError, CompileError

__all__ = ["REACH_LIMIT", "REPETITION_MODES", "Split", "SplitRecord", "describe",
           "explain_failure", "multiplex_candidates", "repetition_mode", "split", "split_program"]

#: Values of the ``repetitions`` compile option.
REPETITION_MODES: tuple[str, ...] = ("auto", "spatial", "temporal")

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


def _fits(amounts: np.ndarray, limits: np.ndarray) -> tuple[bool, float]:
    ratio = float((amounts / limits).max()) if amounts.size else 0.0
    return ratio <= 1.0, ratio


def _resident(stage: Stage, multiplexed: Collection[str], shared: bool) -> tuple[int, int]:
    """Neurons and stored synapse entries (a lower bound) of a stage as placed."""
    r = stage.repetitions if stage.key in multiplexed else 1
    return stage.neurons // r, stage.synapses_stored if shared else stage.synapse_instances // r


def _check_totals(networks: Sequence[SpikingNetwork], profile: HardwareProfile,
                  multiplexed: Sequence[Collection[str]], what: str,
                  stage_lists: Sequence[list[Stage]] | None = None) -> None:
    """Raise when the resident neurons or synapse bits exceed all cores together."""
    cores = profile.n_cores
    if cores is None:
        return
    limits = profile.limits()
    shared = profile.shared_weights_per_core
    stage_lists = stage_lists or [stages(n) for n in networks]
    rows = [(net, st, *_resident(st, mux, shared))
            for net, mux, sts in zip(networks, multiplexed, stage_lists, strict=True)
            for st in sts]
    need = {"neurons": sum(r[2] for r in rows),
            "synapse_bits": sum(r[3] for r in rows) * profile.bits_per_synapse}
    # the budget that needs the most cores is the one to report
    budget = max(need, key=lambda b: need[b] / limits[BUDGETS.index(b)])
    amount, limit = need[budget], limits[BUDGETS.index(budget)]
    if amount > limit * cores:
        net, st, n_res, _ = max(rows, key=lambda r: r[2])
        biggest = net.population[st.populations[0]]
        inst = (f" (one instance of {st.repetitions:,})"
                if any(st.key in m for m in multiplexed) else "")
        n = ceil(amount / limit)
        raise BudgetError(
            f"{what} needs {amount:,} {_BUDGET_TEXT[budget]} but "
            f"{profile.name} has {int(limit):,} per core x {cores} cores = "
            f"{int(limit * cores):,}: at least {n:,} cores "
            f"({ceil(n / profile.cores_per_chip):,} chips of {profile.cores_per_chip} cores, "
            f"{profile.chips} available); the largest population is {describe(biggest)} with "
            f"{n_res:,} neurons{inst}; {_SUGGEST[budget]}", node=biggest.origin.get("node"))


def _too_big(pop: Population, profile: HardwareProfile, amounts: np.ndarray,
             limits: np.ndarray) -> BudgetError:
    worst = np.unravel_index(np.argmax(amounts / limits), amounts.shape)
    budget = BUDGETS[worst[1]]
    return BudgetError(
        f"{describe(pop)}: even one neuron per core needs {int(amounts[worst]):,} "
        f"{_BUDGET_TEXT[budget]}, {profile.name} allows {int(limits[worst[1]]):,} per core; "
        f"{_SUGGEST[budget]}", node=pop.origin.get("node", pop.id))


def split_population(network: SpikingNetwork, pop: Population, profile: HardwareProfile,
                     neurons: np.ndarray | None = None) -> Demand:
    """The fewest uniform blocks (found by growth then bisection) whose every block fits a core.

    ``neurons`` (ascending flat indices, e.g. one instance of a multiplexed stage)
    restricts the blocks to those neurons; ``None`` splits the whole population.

    Raises
    ------
    BudgetError
        If blocks of one neuron still exceed a budget.
    """
    limits = profile.limits()
    pops = network.population
    size = pop.size if neurons is None else len(neurons)
    runs = pop.size // size  # the blocks hold 1/runs of every projection's instances
    instances = sum(synapse_instances(p, pops) for p in network.incoming(pop.id)) // runs
    # fan-in lines are counted when budgeted, or when cheap enough to give the spike traffic
    reach = bool(np.isfinite(limits[1])) or instances <= REACH_LIMIT

    def measure(n: int) -> Demand:
        return block_demand(network, pop.id, Blocks.uniform(pop.id, size, n, neurons=neurons),
                            bits_per_synapse=profile.bits_per_synapse,
                            shared_weights=profile.shared_weights_per_core, reach=reach)

    n = ceil(size / limits[0]) if np.isfinite(limits[0]) else 1
    bad = 0
    if not profile.shared_weights_per_core and np.isfinite(limits[3]):
        # unshared entries sum to the same total for any split: a lower bound on n
        bits = profile.bits_per_synapse * instances
        n = max(n, min(size, ceil(bits / limits[3])))
        bad = n - 1
    attempts = 0
    while True:
        attempts += 1
        d = measure(n)
        ok, ratio = _fits(d.amounts, limits)
        if ok:
            break
        if n == size:
            raise _too_big(pop, profile, d.amounts, limits)
        bad = max(bad, n)
        step = 1 if attempts <= 3 else max(1, n // 8)  # creep first, then grow geometrically
        n = min(size, max(ceil(n * ratio), n + step, bad + 1))
    while n - bad > 1:  # smallest fitting n in (bad, n]
        mid = (bad + n) // 2
        d_mid = measure(mid)
        if _fits(d_mid.amounts, limits)[0]:
            n, d = mid, d_mid
        else:
            bad = mid
    return d


def split(network: SpikingNetwork, profile: HardwareProfile | None = None, *,
          multiplexed: Collection[str] = ()) -> SplitRecord:
    """Cut every neuron population of ``network`` into blocks that fit one core each.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    profile : HardwareProfile, optional
        The target (``None``: ``unbounded``).
    multiplexed : collection of str
        Stages (IR nodes) to time-multiplex: only one instance of each is split.

    Returns
    -------
    SplitRecord

    Raises
    ------
    BudgetError
        The network exceeds all cores together, or one neuron exceeds a core.
    CompileError
        A stage in ``multiplexed`` does not exist or cannot be multiplexed.
    """
    profile = load_profile(profile)
    _check_totals([network], profile, [multiplexed], f"network {network.name!r}")
    return _split_network(network, profile, multiplexed)


def _split_network(network: SpikingNetwork, profile: HardwareProfile,
                   multiplexed: Collection[str],
                   stage_list: list[Stage] | None = None) -> SplitRecord:
    pops = network.population
    by_key = {st.key: st for st in (stage_list or stages(network))}
    for key in multiplexed:
        st = by_key.get(key)
        if st is None or not st.multiplexable:
            why = "no such stage" if st is None else (
                f"{st.repetitions} repetition(s) not on shared matrix pass-through axes")
            raise CompileError(f"network {network.name!r}: stage {key!r} cannot be "
                               f"time-multiplexed ({why}); multiplexable stages: "
                               f"{sorted(k for k, s in by_key.items() if s.multiplexable)}",
                               node=key)
    record = SplitRecord(network=network.name, profile=profile.name,
                         multiplexed={k: by_key[k].repetitions for k in by_key
                                      if k in multiplexed})
    for pid in network.population_order():
        pop = pops[pid]
        if pop.source:
            continue
        key = stage_key(pop)
        record.stage_of[pid] = key
        neurons = instance_neurons(pop, by_key[key].axes) if key in multiplexed else None
        record.demand[pid] = split_population(network, pop, profile, neurons)
    return record


def multiplex_candidates(networks: Sequence[SpikingNetwork], profile: HardwareProfile,
                         stage_lists: Sequence[list[Stage]] | None = None
                         ) -> list[tuple[int, Stage]]:
    """Multiplexable stages of all ``networks`` as ``(network index, stage)``, largest first.

    Size = the cores the stage's neurons and unshared synapse bits need at least
    (unbounded budgets count 0); ties: more repetitions first, then network order.

    Examples
    --------
    >>> from compiler.hardware.reference_networks import dft_network
    >>> [(k, s.key, s.repetitions) for k, s in multiplex_candidates([dft_network()],
    ...                                                            load_profile("loihi"))]
    [(0, 'rng', 256)]
    """
    limits = profile.limits()
    finite = np.where(np.isfinite(limits), limits, np.inf)
    found = []
    for k, sts in enumerate(stage_lists or [stages(n) for n in networks]):
        for i, st in enumerate(sts):
            if st.multiplexable:
                size = max(st.neurons / finite[0],
                           st.synapse_instances * profile.bits_per_synapse / finite[3])
                found.append((-size, -st.repetitions, k, i, st))
    return [(k, st) for *_, k, _, st in sorted(found, key=lambda f: f[:4])]


def repetition_mode(options) -> str:
    """The ``repetitions`` option (default ``"auto"``), checked.

    Raises
    ------
    CompileError
        Not one of :data:`REPETITION_MODES`.
    """
    mode = options.get("repetitions") or "auto"
    if mode not in REPETITION_MODES:
        raise CompileError(f"compile option 'repetitions' = {mode!r} is not one of "
                           f"{', '.join(REPETITION_MODES)}")
    return mode


def _plan(networks, chosen: list[tuple[int, Stage]]) -> list[set[str]]:
    sets: list[set[str]] = [set() for _ in networks]
    for k, st in chosen:
        sets[k].add(st.key)
    return sets


def explain_failure(err: BudgetError, chosen: list[tuple[int, Stage]], mode: str,
                    n_candidates: int) -> BudgetError:
    """``err`` with what the repetition mode tried, and what else could help."""
    if chosen:
        runs = ", ".join(f"{st.key} x{st.repetitions:,}" for _, st in chosen)
        extra = (f" — even with every repeated stage time-multiplexed (one instance each of "
                 f"{runs}); what does not fit is not repeated, so shrink it or add chips")
    elif mode == "spatial" and n_candidates:
        extra = (f"; or time-multiplex the {n_candidates} repeated stage(s) (compile option "
                 "repetitions='auto' or 'temporal', CLI --repetitions)")
    else:
        extra = ""
    return BudgetError(f"{err}{extra}", node=err.node)


def split_program(networks: Sequence[SpikingNetwork], profile: HardwareProfile | None = None,
                  repetitions: str = "auto", *, start: int = 0) -> list[SplitRecord]:
    """Split all networks of a program (resident together) under a repetition mode.

    Parameters
    ----------
    networks : sequence of SpikingNetwork
        The program's networks.
    profile : HardwareProfile, optional
        The target (``None``: ``unbounded``).
    repetitions : {"auto", "spatial", "temporal"}
        ``spatial``: unroll every repetition; ``temporal``: multiplex every
        multiplexable stage; ``auto``: the first plan, spatial then the
        :func:`multiplex_candidates` multiplexed one more at a time, whose resident
        neurons and synapse bits fit all cores together.
    start : int
        ``auto``: the number of candidates to multiplex at least (the place pass
        raises it when the blocks do not pack onto the cores).

    Returns
    -------
    list of SplitRecord

    Raises
    ------
    BudgetError
        Not even the last plan fits (the message says what was multiplexed).

    Examples
    --------
    >>> from compiler.hardware.reference_networks import dft_network
    >>> (rec,) = split_program([dft_network()], load_profile("loihi"))
    >>> rec.multiplexed, rec.blocks["rng"].n_neurons, rec.blocks["rng"].n_blocks
    ({'rng': 256}, 1024, 13)
    """
    profile = load_profile(profile)
    networks = list(networks)
    stage_lists = [stages(n) for n in networks]
    cands = multiplex_candidates(networks, profile, stage_lists)
    counts = {"spatial": [0], "temporal": [len(cands)]}.get(
        repetitions, list(range(min(start, len(cands)), len(cands) + 1)))
    what = (f"network {networks[0].name!r}" if len(networks) == 1 else
            f"the program (networks {', '.join(repr(x.name) for x in networks)})")
    cap = profile.limits() * (profile.n_cores or np.inf)
    for n in counts:
        plan = _plan(networks, cands[:n])
        try:
            _check_totals(networks, profile, plan, what, stage_lists)
        except BudgetError as err:
            if n == counts[-1]:
                raise explain_failure(err, cands[:n], repetitions, len(cands)) from None
            continue
        records, used = [], np.zeros(len(BUDGETS))
        for net, mux, sts in zip(networks, plan, stage_lists, strict=True):
            records.append(_split_network(net, profile, mux, sts))
            used += sum(d.amounts.sum(axis=0) for d in records[-1].demand.values())
            # a core is charged the sum of its blocks: a sum over all cores' limits never fits
            if n != counts[-1] and np.any(used > cap):
                break
        else:
            return records
    return records


@dataclass(frozen=True)
class Split(Pass):
    """Split the program's networks (:func:`split_program`, option ``repetitions``).

    Records ``records["split"]``: one :class:`SplitRecord` per network.
    """

    name: ClassVar[str] = "split"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = load_profile(ctx.target)
        mode = repetition_mode(ctx.options)
        ctx.progress(self.name, f"{len(program.networks)} network(s), repetitions={mode}")
        program.records[self.name] = split_program(program.networks, profile, mode)
        return program
