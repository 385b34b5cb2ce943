r"""The ``split`` pass: cut every neuron population into blocks that each fit one core.

For a population the starting block count is NengoLoihi's rule

.. math:: n = \max\Big(\Big\lceil \tfrac{\text{neurons}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{fan-in lines}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{fan-out lines}}{\max}\Big\rceil,
          \Big\lceil \tfrac{\text{synapse bits}}{\max}\Big\rceil\Big)

evaluated on the worst block (a fan-in that does not shrink with the block, as a
dense matrix's, makes it grow); the blocks (equal sizes ±1, contiguous in memory
order) are then measured exactly (:class:`compiler.hardware.demand.DemandModel`),
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
from dataclasses import dataclass
from math import ceil
from typing import ClassVar

import numpy as np

from compiler.hardware import BUDGETS, Blocks, HardwareProfile, load_profile
from compiler.hardware.demand import Demand, demand_model, synapse_instances
from compiler.hardware.repetition import Stage, instance_neurons, stage_key, stages
from compiler.memo import CompileMemo
from compiler.passes.base import CompileContext, Pass
from compiler.passes.split_budget import check_totals, explain_failure, fits, too_big
from compiler.passes.split_plan import (
    REPETITION_MODES,
    multiplex_candidates,
    plan,
    repetition_mode,
)
from compiler.passes.split_record import SplitRecord, describe
from compiler.program import CompiledProgram
from compiler.snn import Population, SpikingNetwork
from ir.errors import BudgetError, CompileError

# REPETITION_MODES, SplitRecord, describe, explain_failure, multiplex_candidates and
# repetition_mode live in split_plan / split_record / split_budget; importable from here too
__all__ = ["REACH_LIMIT", "REPETITION_MODES", "Split", "SplitRecord", "describe",
           "explain_failure", "multiplex_candidates", "repetition_mode", "split", "split_program",
           "split_population"]

#: Without a fan-in budget, fan-in lines (and so the spike traffic) are counted only for
#: populations receiving at most this many synapse instances.
REACH_LIMIT = 1 << 27


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
    # fan-in lines are measured while searching only when budgeted; they are counted for the
    # result when budgeted, or when cheap enough to give the spike traffic
    budgeted = bool(np.isfinite(limits[1]))
    reach = budgeted or instances <= REACH_LIMIT
    model = demand_model(network, pop.id, neurons,
                         shared_weights=profile.shared_weights_per_core)
    bits = profile.bits_per_synapse

    def blocks(n: int) -> Blocks:
        return Blocks.uniform(pop.id, size, n, neurons=neurons)

    def measure(n: int) -> np.ndarray:
        return model.amounts(blocks(n), bits_per_synapse=bits, fan_in=budgeted)

    n = ceil(size / limits[0]) if np.isfinite(limits[0]) else 1
    bad = 0
    if not profile.shared_weights_per_core and np.isfinite(limits[3]):
        # unshared entries sum to the same total for any split: a lower bound on n
        n = max(n, min(size, ceil(bits * instances / limits[3])))
        bad = n - 1
    attempts = 0
    while True:
        attempts += 1
        amounts = measure(n)
        ok, ratio = fits(amounts, limits)
        if ok:
            break
        if n == size:
            raise too_big(pop, profile, amounts, limits)
        bad = max(bad, n)
        step = 1 if attempts <= 3 else max(1, n // 8)  # creep first, then grow geometrically
        n = min(size, max(ceil(n * ratio), n + step, bad + 1))
    while n - bad > 1:  # smallest fitting n in (bad, n]
        mid = (bad + n) // 2
        if fits(measure(mid), limits)[0]:
            n = mid
        else:
            bad = mid
    return model.demand(blocks(n), bits_per_synapse=bits, reach=reach)


def split(network: SpikingNetwork, profile: HardwareProfile | str = "unbounded", *,
          multiplexed: Collection[str] = ()) -> SplitRecord:
    """Cut every neuron population of ``network`` into blocks that fit one core each.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    profile : HardwareProfile or str, default "unbounded"
        The target: a profile, or a built-in name or YAML path (loaded).
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
    check_totals([network], profile, [multiplexed], f"network {network.name!r}")
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


def split_program(networks: Sequence[SpikingNetwork], profile: HardwareProfile | str = "unbounded",
                  repetitions: str = "auto", *, start: int = 0,
                  memo: CompileMemo | None = None) -> list[SplitRecord]:
    """Split all networks of a program (resident together) under a repetition mode.

    Parameters
    ----------
    networks : sequence of SpikingNetwork
        The program's networks.
    profile : HardwareProfile or str, default "unbounded"
        The target: a profile, or a built-in name or YAML path (loaded).
    repetitions : {"auto", "spatial", "temporal"}
        ``spatial``: unroll every repetition; ``temporal``: multiplex every
        multiplexable stage; ``auto``: the first plan, spatial then the
        :func:`multiplex_candidates` multiplexed one more at a time, whose resident
        neurons and synapse bits fit all cores together.
    start : int
        ``auto``: the number of candidates to multiplex at least (the place pass
        raises it when the blocks do not pack onto the cores).
    memo : CompileMemo, optional
        A network's split under the same stages multiplexed, kept from an earlier
        attempt of a measured compile (:meth:`compiler.memo.CompileMemo.split`).

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
        chosen = plan(networks, cands[:n])
        try:
            check_totals(networks, profile, chosen, what, stage_lists)
        except BudgetError as err:
            if n == counts[-1]:
                raise explain_failure(err, cands[:n], repetitions, len(cands)) from None
            continue
        records, used = [], np.zeros(len(BUDGETS))
        for net, mux, sts in zip(networks, chosen, stage_lists, strict=True):
            if memo is None:
                records.append(_split_network(net, profile, mux, sts))
            else:
                records.append(memo.split(net, profile, mux, lambda net=net, mux=mux, sts=sts:
                                          _split_network(net, profile, mux, sts)))
            used += sum(_known(d, cap).sum(axis=0) for d in records[-1].demand.values())
            # a core is charged the sum of its blocks: a sum over all cores' limits never fits
            if n != counts[-1] and np.any(used > cap):
                break
        else:
            return records
    return records


def _known(demand: Demand, cap: np.ndarray) -> np.ndarray:
    """A demand's amounts; fan-in lines still pending only when their cap is unbounded."""
    return demand.amounts if np.isfinite(cap[1]) else demand.amounts_counted


@dataclass(frozen=True)
class Split(Pass):
    """Split the program's networks (:func:`split_program`, option ``repetitions``).

    Records ``records["split"]``: one :class:`SplitRecord` per network.

    Attributes
    ----------
    repetitions : {"auto", "spatial", "temporal"}
        How repeated stages are laid out (compile option ``repetitions``).
    """

    name: ClassVar[str] = "split"
    repetitions: str = "auto"

    def __post_init__(self) -> None:
        repetition_mode(self.repetitions)

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = ctx.target
        mode = self.repetitions
        ctx.progress(self.name, f"{len(program.networks)} network(s), repetitions={mode}")
        program.records.splits = split_program(program.networks, profile, mode,
                                               memo=ctx.memo)
        return program
