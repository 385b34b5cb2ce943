r"""Build a Brian2 network that runs a :class:`~compiler.snn.SpikingNetwork` step for step.

Every object runs in Brian2's ``end`` slot with ``dt = 1 ms = 1 step``, ordered
so one Brian2 time step is exactly one step of the reference engine
(:mod:`backends.reference.step`).  For the population at position ``k`` of
:meth:`~compiler.snn.SpikingNetwork.population_order` (zero-delay edges run
source before target) the five sub-slots ``order = 5k + s`` are:

====  ==============================================================
s=0   the ``Synapses`` pathways *into* the population deliver ``I_in += w``
s=1   the neuron update (:mod:`backends.brian2.equations`), ``run_regularly``
s=2   the threshold (a ``SpikeGeneratorGroup`` for an encoder's source)
s=3   the reset
s=4   the ``SpikeMonitor``
====  ==============================================================

A pathway pushes its source's spikes of the last threshold it saw.  For a
*forward* projection (source earlier in the order) that is this step's, so the
Brian2 delay is the projection's delay ``d``; for a *backward* one (source at
or after the target: recurrent, ``d >= 1`` by validation) it is the previous
step's, so the Brian2 delay is ``d - 1``.  A spike of step ``t`` therefore
adds to the target's ``I[t + d]``, as in :mod:`compiler.snn.projections`.

Frames are independent copies of every population (``n_frames × size``
neurons) with synapses replicated per frame.  Brian2 stores every synapse
instance (no weight sharing).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from backends.brian2.equations import neuron_code
from backends.brian2.resonator import (
    ON_PRE,
    SYNAPSE_MODEL,
    compartment_constants,
    fan_to_compartments,
    resonator_code,
)
from backends.brian2.synapses import EXPANDERS, SynapseList, expand_projection
from compiler.snn.network import SpikingNetwork
from compiler.snn.resonator import ResonatorParams
from ir.errors import SimulationError

__all__ = ["Brian2Model", "build_model", "SUB_SLOTS"]

#: Brian2 ``order`` sub-slots per population (pathways in, update, threshold, reset, monitor).
SUB_SLOTS = 5


@dataclass(frozen=True, eq=False)
class Brian2Model:
    """A built Brian2 network and the handles needed to read it back.

    Attributes
    ----------
    net : brian2.Network
        Every object below.
    groups, monitors : dict
        Per population id, its ``NeuronGroup`` / ``SpikeGeneratorGroup`` and ``SpikeMonitor``.
    synapses : dict
        Per projection id, the Brian2 ``Synapses`` (absent when it has no synapse) and the
        replicated :class:`SynapseList` with the true delays.
    n_frames : int
        Independent copies of the network.
    """

    net: Any
    groups: dict[str, Any]
    monitors: dict[str, Any]
    synapses: dict[str, tuple[Any, SynapseList]]
    n_frames: int


def _at(obj: Any, k: int, sub: int) -> None:
    obj.when, obj.order = "end", SUB_SLOTS * k + sub


def build_model(
    b2: Any,
    network: SpikingNetwork,
    trains: Mapping[str, Any],
    n_frames: int,
    expanders: Mapping[type, Callable[..., SynapseList]] = EXPANDERS,
) -> Brian2Model:
    """Create the Brian2 objects of ``network`` for ``n_frames`` frames of input spikes.

    Parameters
    ----------
    b2 : module
        The ``brian2`` module.
    network : SpikingNetwork
        A validated network.
    trains : mapping
        Per source population, its spike train (:func:`backends.reference.encoding.encode_inputs`).
    n_frames : int
        Frames in the batch.
    expanders : mapping
        Synapse expander per projection kind (default :data:`~backends.brian2.synapses.EXPANDERS`).

    Returns
    -------
    Brian2Model

    Raises
    ------
    SimulationError
        For a projection kind without an expander (naming it).
    """
    ms = b2.ms
    pops = network.population
    order = network.population_order()
    index = {pid: k for k, pid in enumerate(order)}
    groups, monitors, synapses = {}, {}, {}
    for k, pid in enumerate(order):
        pop, n = pops[pid], n_frames * pops[pid].size
        if pop.source:
            flat, steps = trains[pid].all_events()
            group = b2.SpikeGeneratorGroup(n, np.asarray(flat, np.int64),
                                           np.asarray(steps, np.float64) * ms, dt=1 * ms)
            _at(group, k, 2)
        else:
            resonator = isinstance(pop.params, ResonatorParams)
            code = (resonator_code if resonator else neuron_code)(pop.params, network.n_steps)
            namespace = {**code.constants,
                         **{name: b2.TimedArray(getattr(code, name), dt=1 * ms)
                            for name in ("bias", "input_on", "spiking_on")},
                         **{name: b2.TimedArray(values, dt=1 * ms)
                            for name, values in code.timed.items()}}
            group = b2.NeuronGroup(n, code.model, threshold=code.threshold, reset=code.reset,
                                   namespace=namespace, dt=1 * ms)
            scale = pop.params.scale_of(pop.shape)
            if resonator:
                for name, values in compartment_constants(pop.params, pop.shape,
                                                          n_frames).items():
                    setattr(group, name, values)
            elif scale is not None:
                group.c = np.tile(scale, n_frames)
            updater = group.run_regularly(code.update, dt=1 * ms)
            _at(updater, k, 1)
            _at(group.thresholder["spike"], k, 2)
            _at(group.resetter["spike"], k, 3)
        monitors[pid] = b2.SpikeMonitor(group)
        _at(monitors[pid], k, 4)
        groups[pid] = group
    for proj in network.projections:
        if type(proj) not in expanders:
            raise SimulationError(f"projection {proj.id!r}: the Brian2 backend has no synapse "
                                  f"expander for kind {proj.kind!r}; known: "
                                  f"{sorted(getattr(t, 'kind', t.__name__) for t in expanders)}",
                                  node=proj.id)
        src, tgt = pops[proj.source], pops[proj.target]
        syn = expand_projection(proj, src, tgt, expanders).replicate(n_frames, src.size,
                                                                     tgt.size)
        if not len(syn):
            continue
        backward = int(index[proj.source] >= index[proj.target])
        if isinstance(tgt.params, ResonatorParams):  # the folded drive of all compartments
            pre, post, wx, wy, delay = fan_to_compartments(syn)
            s = b2.Synapses(groups[proj.source], groups[proj.target], SYNAPSE_MODEL,
                            on_pre=ON_PRE, dt=1 * ms)
            s.connect(i=pre, j=post)
            s.wx, s.wy = wx, wy
        else:
            s = b2.Synapses(groups[proj.source], groups[proj.target], "w : 1 (constant)",
                            on_pre="I_in_post += w", dt=1 * ms)
            s.connect(i=syn.pre, j=syn.post)
            s.w = syn.weight
            delay = syn.delay
        s.delay = (delay - backward).astype(np.float64) * ms
        _at(s.pre, index[proj.target], 0)
        synapses[proj.id] = (s, syn)
    objects = [*groups.values(), *monitors.values(), *(s for s, _ in synapses.values())]
    return Brian2Model(net=b2.Network(*objects), groups=groups, monitors=monitors,
                       synapses=synapses, n_frames=n_frames)
