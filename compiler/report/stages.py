r"""Per-stage rows (the bottom of Vogginger et al.'s Table 3): one row per IR node of a network.

A **stage** is the set of populations whose ``origin["node"]`` is one IR node
(populations without an origin form a stage of their own id).  Its

* ``repetitions`` :math:`R` is the gcd of its projections' repetition counts
  (a matrix shared over repetition axes counts ``source.size / n_in``; a stencil 1);
* ``inputs`` are the distinct neurons outside the stage with a synapse into it,
  ``neurons`` its non-source neurons, ``synapses`` its projections' instances
  (matrix: repetitions × stored synapses; stencil: neurons × taps, as
  :meth:`~compiler.snn.SpikingNetwork.n_synapse_instances` counts) — each **per
  repetition**, i.e. divided by :math:`R`, with the ``*_total`` fields undivided;
* ``synapse_memory_bits`` what the split stores for it on the target, ``cores``
  the cores its blocks occupy;
* ``multiplexed`` whether the split time-multiplexes it: then one instance is
  placed (``cores``, ``blocks`` and ``synapse_memory_bits`` are for that
  instance) and run ``repetitions`` times per frame of ``time_steps`` steps each
  (``steps_per_frame`` = :math:`R T`, else :math:`T`);
* ``spikes`` / ``synaptic_events`` per frame: the bound of
  :func:`compiler.hardware.activity.spike_bound` times the population sizes /
  synapse instances, and the measured means when a simulation is given.
"""

from __future__ import annotations

import numpy as np

from compiler.hardware.activity import spike_bound
from compiler.hardware.demand import has_synapse_out, projection_info
from compiler.hardware.repetition import projection_repetitions as repetitions
from compiler.hardware.repetition import stages
from compiler.snn import SpikingNetwork

__all__ = ["measured_rows", "stage_rows", "nominal_synapses", "repetitions"]


def nominal_synapses(proj, pops) -> int:
    """Synapse instances as the paper counts them (stencil: neurons × taps, edges ignored)."""
    return proj.n_synapse_instances(pops[proj.source], pops[proj.target])


def _reached(network: SpikingNetwork, source: str, projs: list) -> int:
    """Neurons of ``source`` with a synapse in any of ``projs`` (vectorized in chunks)."""
    pops = network.population
    pop = pops[source]
    infos = [projection_info(p, pop, pops[p.target]) for p in projs]
    if all(i.shared_matrix and i.proj.contract == projs[0].contract for i in infos):
        rownz = np.logical_or.reduce([i.rownz for i in infos])  # same rows in every repetition
        return repetitions(projs[0], pops) * int(rownz.sum())
    total = 0
    for lo in range(0, pop.size, 1 << 22):
        flat = np.arange(lo, min(pop.size, lo + (1 << 22)), dtype=np.int64)
        has = np.zeros(flat.size, bool)
        for info in infos:
            has |= has_synapse_out(info, pop, flat)
        total += int(has.sum())
    return total


def stage_rows(network: SpikingNetwork, *, split=None, placement=None, net_index: int = 0,
               bits_per_synapse: int = 0, sim=None) -> list[dict]:
    """One row per stage of ``network`` (see the module docstring).

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    split : SplitRecord, optional
        Its split (for ``synapse_memory_bits`` and ``blocks``).
    placement : Placement, optional
        The placement (for ``cores``).
    net_index : int
        The network's index in the placement.
    bits_per_synapse : int
        The target's entry width.
    sim : SimResult, optional
        A simulation of ``network`` (for the measured spikes and events).

    Returns
    -------
    list of dict
    """
    pops = network.population
    bound = spike_bound(network)
    rows = []
    for stage in stages(network):
        key, r = stage.key, stage.repetitions
        neurons = [pops[pid] for pid in stage.populations]
        ids = set(stage.populations)
        projs = [q for q in network.projections if q.target in ids]
        outside: dict[str, list] = {}
        for q in projs:
            if q.source not in ids:
                outside.setdefault(q.source, []).append(q)
        n_in = sum(_reached(network, s, qs) for s, qs in outside.items())
        n_neu = sum(p.size for p in neurons)
        n_syn = sum(nominal_synapses(q, pops) for q in projs)
        mux = split is not None and key in split.multiplexed
        row = {
            "node": key, "motif": stage.motif, "network": network.name,
            "inputs": n_in // r if n_in % r == 0 else n_in / r,
            "neurons": n_neu // r if n_neu % r == 0 else n_neu / r,
            "synapses": n_syn // r if n_syn % r == 0 else n_syn / r,
            "time_steps": network.n_steps, "repetitions": r,
            "multiplexed": mux,
            "steps_per_frame": network.n_steps * (r if mux else 1),
            "inputs_total": n_in, "neurons_total": n_neu, "synapses_total": n_syn,
            "synapses_stored": sum(q.n_synapses for q in projs),
            "spikes_bound": sum(p.size * bound[p.id] for p in neurons),
            "synaptic_events_bound": sum(bound[q.source] * nominal_synapses(q, pops)
                                         for q in projs),
        }
        if split is not None:
            dem = [split.demand[p.id] for p in neurons if p.id in split.demand]
            row["blocks"] = sum(d.blocks.n_blocks for d in dem)
            row["synapse_memory_bits"] = int(sum(int(d.entries.sum()) for d in dem)
                                             * bits_per_synapse)
        if placement is not None:
            row["cores"] = len({c for p in neurons for c in placement.cores_of(net_index, p.id)})
        if sim is not None:
            row.update(_measured(neurons, projs, sim))
        rows.append(row)
    return rows


def _measured(neurons, projs, sim) -> dict:
    return {"spikes_measured": sum(sim.spike_counts.get(p.id, 0) for p in neurons)
            / sim.n_frames,
            "synaptic_events_measured": sum(sim.synaptic_events.get(q.id, 0) for q in projs)
            / sim.n_frames}


def measured_rows(network: SpikingNetwork, sim) -> dict[str, dict]:
    """Per stage key, the measured spikes and synaptic events per frame of a simulation.

    The ``spikes_measured`` and ``synaptic_events_measured`` fields of :func:`stage_rows`
    (mean per frame over ``sim.n_frames``), for a report built before the simulation.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from compiler.snn import Population, SpikingNetwork
    >>> net = SpikingNetwork(name="m", n_steps=4, populations=[Population(id="y", shape={"o": 4})])
    >>> measured_rows(net, SimpleNamespace(spike_counts={"y": 6}, synaptic_events={}, n_frames=3))
    {'y': {'spikes_measured': 2.0, 'synaptic_events_measured': 0.0}}
    """
    pops = network.population
    out = {}
    for stage in stages(network):
        ids = set(stage.populations)
        projs = [q for q in network.projections if q.target in ids]
        out[stage.key] = _measured([pops[pid] for pid in stage.populations], projs, sim)
    return out
