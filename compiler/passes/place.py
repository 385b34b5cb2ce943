r"""The ``place`` pass: put the split blocks onto cores and chips, and count spike traffic.

The placer is a replaceable function ``placer(demand, limits, affinity, n_cores) ->
core`` (see :data:`Placer`); the default :func:`greedy_placer` is first-fit
decreasing with locality.  A core holding several blocks is charged the **sum**
of their demands (conservative: a source reaching two blocks on one core is
counted twice, and shared weights once per block).

Traffic per frame (:mod:`compiler.passes.place_traffic`) counts one message per
spike and destination core of every source neuron: from spike sources (encoders)
it is the host input; the others are inter-core, of which those crossing chips
(``core // cores_per_chip``) are inter-chip.

**Chips.** On a profile of several chips the used cores are then grouped into chips so that
the heaviest spike traffic stays on-chip (:mod:`compiler.passes.place_chips`; option
``chip_assignment="traffic"``, or ``"placer"`` to keep the placer's ``core // cores_per_chip``);
the placement then holds the chip-to-chip message matrix (``chip_messages``).

**Time-multiplexed stages** (see :mod:`compiler.passes.split`): only one
instance is placed and it runs :math:`R` times per frame, so messages into its
blocks count :math:`R` times; synapses that cross the boundary of a multiplexed
stage (into it from anything else, or out of it into a spatial stage) carry
spikes replayed from the stage's frame buffer, counted as ``buffered``.

Examples
--------
>>> import numpy as np
>>> greedy_placer(np.array([[3.0], [2.0], [2.0]]), np.array([4.0]),
...               np.zeros((3, 3)), None).tolist()
[0, 1, 1]
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from compiler.hardware import BUDGETS, HardwareProfile, load_profile
from compiler.hardware.activity import measured_spikes, spike_bound
from compiler.memo import CompileMemo
from compiler.passes.base import CompileContext, Pass
from compiler.passes.place_chips import chip_assignment as assign_chips
from compiler.passes.place_chips import chip_matrix
from compiler.passes.place_greedy import Placer, greedy_placer
from compiler.passes.place_traffic import block_affinity, core_messages, spike_traffic
from compiler.passes.split import split, split_program
from compiler.passes.split_budget import explain_failure
from compiler.passes.split_plan import multiplex_candidates, repetition_mode
from compiler.passes.split_record import SplitRecord, describe
from compiler.program import CompiledProgram
from compiler.snn import SpikingNetwork
from ir.errors import BudgetError, CompileError

# Placer and greedy_placer live in place_greedy; importable from here too
__all__ = ["Place", "Placement", "Placer", "greedy_placer", "place"]

log = logging.getLogger(__name__)


@dataclass
class Placement:
    """Where every block went, per-core usage and spike traffic.

    Attributes
    ----------
    items : list of (int, str, int)
        ``(network index, population id, block index)`` of each block.
    core : ndarray of int
        Core of each item; ``chip = core // cores_per_chip``.
    usage : ndarray, shape (n_cores_used, 4)
        Summed demand per core (:data:`~compiler.hardware.BUDGETS` order).
    utilisation : ndarray, shape (n_cores_used, 4)
        ``usage / limits`` (0 for unbounded budgets).
    traffic : dict
        Messages per frame: ``host_input``, ``inter_core``, ``inter_chip``, ``buffered``
        (replayed across a multiplexed stage's boundary), ``basis`` (``"bound"`` or
        ``"measured"``) and ``not_counted`` (populations whose fan-in was too large to
        enumerate without a fan-in budget; their incoming traffic is missing).
    multiplexed : list of dict
        ``network``, ``stage``, ``repetitions`` of each time-multiplexed stage: its items
        are the blocks of one instance, run ``repetitions`` times per frame.
    chip_messages : ndarray, shape (n_chips, n_chips), or None
        On a multi-chip profile: messages per frame from chip ``i`` to chip ``j`` (the
        diagonal: between cores of one chip); ``None`` on a single chip.
    network_inter_chip : list of float
        On a multi-chip profile: inter-chip messages per frame of each network.
    """

    profile: str
    items: list[tuple[int, str, int]]
    core: np.ndarray
    chip: np.ndarray
    usage: np.ndarray
    utilisation: np.ndarray
    traffic: dict = field(default_factory=dict)
    multiplexed: list[dict] = field(default_factory=list)
    chip_messages: np.ndarray | None = None
    network_inter_chip: list[float] = field(default_factory=list)

    @property
    def n_cores(self) -> int:
        """Cores used."""
        return len(self.usage)

    @property
    def n_chips(self) -> int:
        """Chips used."""
        return int(self.chip.max()) + 1 if self.chip.size else 0

    def cores_of(self, network: int, population: str) -> list[int]:
        """Distinct cores holding blocks of one population."""
        return sorted({int(c) for (i, p, _), c in zip(self.items, self.core, strict=True)
                       if i == network and p == population})

    def to_dict(self) -> dict:
        """A JSON-able summary."""
        return {"profile": self.profile, "cores": self.n_cores, "chips": self.n_chips,
                "max_utilisation": dict(zip(BUDGETS, self.utilisation.max(axis=0, initial=0)
                                            .round(4).tolist(), strict=True)),
                "traffic": self.traffic, "multiplexed": self.multiplexed}


def place(networks: Sequence[SpikingNetwork], splits: Sequence[SplitRecord] | None = None,
          profile: HardwareProfile | str = "unbounded", *, placer: Placer = greedy_placer,
          sim_results: Sequence | None = None, chip_assignment: str = "traffic",
          memo: CompileMemo | None = None) -> Placement:
    """Place the blocks of all ``networks`` (resident together) onto the profile's cores.

    Parameters
    ----------
    networks : sequence of SpikingNetwork
        The program's networks.
    splits : sequence of SplitRecord, optional
        Their splits (computed here when omitted).
    profile : HardwareProfile or str, default "unbounded"
        The target: a profile, or a built-in name or YAML path (loaded).
    placer : Placer
        The placement function (default :func:`greedy_placer`).
    sim_results : sequence of SimResult, optional
        One per network: traffic from measured spike counts instead of the bound.
    chip_assignment : {"traffic", "placer"}
        On several chips: group the used cores into chips to keep the heaviest traffic
        on-chip (:mod:`~compiler.passes.place_chips`), or keep ``core // cores_per_chip``.
    memo : CompileMemo, optional
        Results kept across the attempts of a measured compile (:mod:`compiler.memo`): a
        network's spike traffic when its blocks sit on the same cores.

    Returns
    -------
    Placement

    Raises
    ------
    BudgetError
        If the blocks do not fit on ``cores_per_chip * chips`` cores.

    Examples
    --------
    >>> from compiler.snn import Population, SpikingNetwork
    >>> net = SpikingNetwork(name="p", n_steps=1,
    ...                      populations=[Population(id="y", shape={"o": 2500})])
    >>> pl = place([net], profile=load_profile("loihi"))
    >>> pl.n_cores, pl.usage[:, 0].tolist()
    (3, [833.0, 833.0, 834.0])
    """
    profile = load_profile(profile)
    networks = list(networks)
    splits = list(splits) if splits is not None else [split(n, profile) for n in networks]
    items, offsets, demand = [], [], []
    for k, rec in enumerate(splits):
        off = {}
        for pid, dem in rec.demand.items():
            off[pid] = len(items)
            items += [(k, pid, b) for b in range(dem.blocks.n_blocks)]
            demand.append(dem.amounts)
        offsets.append(off)
    demand_arr = np.concatenate(demand).astype(np.float64) if demand else np.zeros((0, 4))
    limits = profile.limits()
    core = np.asarray(placer(demand_arr, limits, block_affinity(splits, offsets),
                             profile.n_cores), dtype=np.int64)
    if (core < 0).any():
        k, pid, _ = items[int(np.argmax(core < 0))]
        pop = networks[k].population[pid]
        raise BudgetError(
            f"{describe(pop)}: the {len(items):,} blocks of the program do not fit on "
            f"{profile.n_cores} cores of {profile.name} ({profile.chips} chip(s) of "
            f"{profile.cores_per_chip}); {int((core < 0).sum()):,} blocks were left over; use "
            "more chips (a profile file with a larger 'chips') or shrink the network",
            node=pop.origin.get("node", pid))
    if chip_assignment not in ("traffic", "placer"):
        raise CompileError(f"option 'chip_assignment' = {chip_assignment!r} is not one of "
                           "traffic, placer")
    n_used = int(core.max()) + 1 if core.size else 0
    spikes = ([measured_spikes(n, s) for n, s in zip(networks, sim_results, strict=True)]
              if sim_results is not None else [spike_bound(n) for n in networks])
    cpc = profile.cores_per_chip
    board = bool(cpc) and (profile.chips or 0) > 1
    chip_msgs, per_net = None, []
    if board:
        msgs = core_messages(networks, splits, offsets, core, spikes)
        if chip_assignment == "traffic" and n_used > cpc:
            new = assign_chips(sum(msgs), cpc)
            core = new[core]
            msgs = [_renumbered(m, new) for m in msgs]
        n_chip = -(-n_used // cpc)
        mats = [chip_matrix(m, np.arange(n_used) // cpc, n_chip) for m in msgs]
        chip_msgs = sum(mats) if mats else np.zeros((n_chip, n_chip))
        per_net = [float(x.sum() - np.trace(x)) for x in mats]
    usage = np.zeros((n_used, 4))
    np.add.at(usage, core, demand_arr)
    util = np.where(np.isfinite(limits), usage / np.where(np.isfinite(limits), limits, 1), 0.0)
    traffic = spike_traffic(networks, splits, offsets, core, cpc, spikes, memo=memo)
    traffic["basis"] = "measured" if sim_results is not None else "bound"
    chip = core // cpc if cpc else np.zeros_like(core)
    mux = [{"network": rec.network, "stage": key, "repetitions": r}
           for rec in splits for key, r in rec.multiplexed.items()]
    return Placement(profile=profile.name, items=items, core=core, chip=chip, usage=usage,
                     utilisation=util, traffic=traffic, multiplexed=mux,
                     chip_messages=chip_msgs, network_inter_chip=per_net)


def _renumbered(m, new: np.ndarray):
    m = m.tocoo()
    return type(m)((m.data, (new[m.row], new[m.col])), shape=m.shape).tocsr()


@dataclass(frozen=True)
class Place(Pass):
    """Place the program's networks (after ``split``); record ``records["placement"]``.

    With ``repetitions="auto"``, blocks that do not pack onto the cores make it
    multiplex the next candidate stage, split again (``records["split"]`` is
    replaced) and retry.

    Attributes
    ----------
    placer : Placer
        The placement function.
    repetitions : {"auto", "spatial", "temporal"}
        The ``repetitions`` option, as :class:`~compiler.passes.split.Split`'s.
    chip_assignment : {"traffic", "placer"}
        As :func:`place`'s.
    """

    name: ClassVar[str] = "place"
    placer: Placer = greedy_placer
    repetitions: str = "auto"
    chip_assignment: str = "traffic"

    def __post_init__(self) -> None:
        repetition_mode(self.repetitions)
        if self.chip_assignment not in ("traffic", "placer"):
            raise CompileError(f"option 'chip_assignment' = {self.chip_assignment!r} is not one "
                               "of traffic, placer")

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        profile = ctx.target
        mode = self.repetitions
        networks = program.networks
        splits = program.records.splits or split_program(networks, profile, mode,
                                                         memo=ctx.memo)
        cands = multiplex_candidates(networks, profile)
        while True:
            try:
                placement = place(networks, splits, profile, placer=self.placer,
                                  chip_assignment=self.chip_assignment, memo=ctx.memo)
                break
            except BudgetError as err:
                n = sum(len(r.multiplexed) for r in splits)
                if mode != "auto" or n >= len(cands):
                    raise explain_failure(err, cands[:n], mode, len(cands)) from None
                # the blocks did not pack: multiplex one more stage and split again
                ctx.progress(self.name, f"multiplexing {n + 1} stage(s)")
                log.info("the blocks did not pack (%s); time-multiplexing %d stage(s)",
                         err, n + 1)
                splits = split_program(networks, profile, mode, start=n + 1, memo=ctx.memo)
        program.records.splits = splits
        program.records.placement = placement
        return program
