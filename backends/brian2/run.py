"""Run a :class:`~compiler.snn.SpikingNetwork` in Brian2 and read it back like the reference.

:func:`simulate_brian2` encodes the inputs with the reference's own trains
(:func:`backends.reference.encoding.encode_inputs`, so both see identical input
spikes), builds the Brian2 network (:mod:`backends.brian2.build`), runs it for
``n_steps`` steps and turns the monitors into the reference's
:class:`~backends.reference.result.Activity`, decoded by the reference's
decoders.  Only ``float64`` arithmetic is modelled.

Brian2 is an optional extra (``pip install radarsnn[brian2]``); it is imported
when a simulation runs, never at import time of this package.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from backends.brian2.build import Brian2Model, build_model
from backends.reference.decoding import check_decoders, decode_outputs
from backends.reference.encoding import encode_inputs
from backends.reference.input_range import DEFAULT_POLICY
from backends.reference.result import Activity, SimResult, first_steps
from compiler.snn.network import SpikingNetwork
from ir.errors import SimulationError

__all__ = ["import_brian2", "simulate_brian2", "read_activity", "TARGETS"]

#: Brian2 code-generation targets this backend accepts.
TARGETS = ("numpy", "cython")


def import_brian2() -> Any:
    """The ``brian2`` module, or a :class:`SimulationError` saying how to install it.

    Raises
    ------
    SimulationError
        If Brian2 is missing or fails to import (e.g. on an unsupported numpy).
    """
    try:
        return importlib.import_module("brian2")
    except Exception as exc:  # ImportError, or brian2 breaking on this numpy at import
        raise SimulationError(
            f"the Brian2 backend needs brian2, which failed to import ({type(exc).__name__}: "
            f"{exc}); install the extra: pip install 'radarsnn[brian2]' (see docs/interop.md "
            "for the pinned brian2/numpy pair)") from None


def read_activity(model: Brian2Model, network: SpikingNetwork, record: bool = False) -> Activity:
    """First spikes, counts, membranes, synaptic events (and rasters) of a run Brian2 model.

    Synaptic events are counted as the reference does: every source spike whose
    delivery step ``t + d`` falls inside the frame, times the synapses of delay ``d``.
    """
    b2 = importlib.import_module("brian2")
    n_steps, n_frames = network.n_steps, model.n_frames
    pops = network.population
    first, counts, spikes = {}, {}, {}
    rasters = {} if record else None
    for pid, mon in model.monitors.items():
        n = n_frames * pops[pid].size
        idx = np.asarray(mon.i[:], np.int64)
        steps = np.rint(np.asarray(mon.t[:] / b2.ms)).astype(np.int64)
        earliest = np.full(n, n_steps, np.int64)
        np.minimum.at(earliest, idx, steps)
        first[pid] = np.where(earliest < n_steps, earliest, -1).reshape(n_frames, -1)
        counts[pid] = np.bincount(idx, minlength=n).reshape(n_frames, -1)
        spikes[pid] = (idx, steps)
        if rasters is not None:
            f, neuron = np.divmod(idx, pops[pid].size)
            rasters[pid] = np.zeros((n_frames, n_steps, pops[pid].size), bool)
            rasters[pid][f, steps, neuron] = True
    events = dict.fromkeys((p.id for p in network.projections), 0)
    for pid, (_, syn) in model.synapses.items():
        proj = network.projection[pid]
        idx, steps = spikes[proj.source]
        n_src = n_frames * pops[proj.source].size
        for d in np.unique(syn.delay):
            live = np.bincount(idx[steps < n_steps - d], minlength=n_src)
            events[pid] += int(live[syn.pre[syn.delay == d]].sum())
    membrane = {pid: np.asarray(g.v[:], np.float64).reshape(n_frames, -1)
                for pid, g in model.groups.items() if not pops[pid].source}
    return Activity(first_spike=first, counts=counts, membrane=membrane,
                    synaptic_events=events, rasters=rasters)


def simulate_brian2(
    network: SpikingNetwork,
    inputs: Mapping[str, np.ndarray],
    *,
    target: str = "numpy",
    record_spikes: bool = False,
    out_of_range: str | Mapping[str, str] = DEFAULT_POLICY,
    b2: Any = None,
) -> SimResult:
    """Simulate ``network`` on ``inputs`` in Brian2; the result reads like the reference's.

    Parameters
    ----------
    network : SpikingNetwork
        The network (validated here).
    inputs : mapping of port to ndarray
        As for :func:`backends.reference.simulate` (optional leading frames axis).
    target : {"numpy", "cython"}
        Brian2's code-generation target (``numpy`` needs no C compiler).
    record_spikes : bool
        Return full spike rasters in :attr:`SimResult.spikes`.
    out_of_range : {"reject", "warn", "clip"} or mapping of port to it
        As for :func:`backends.reference.simulate` (refuse by default; clipped
        values are counted in :attr:`SimResult.clipped`).
    b2 : module, optional
        The ``brian2`` module (imported by default).

    Returns
    -------
    SimResult
        ``mode`` is ``"brian2-<target>"``.

    Raises
    ------
    SimulationError
        Brian2 missing, an unknown target, or bad inputs.
    NetworkError
        If the network does not validate or a decoder cannot be honoured.

    Notes
    -----
    Spike steps equal :func:`backends.reference.simulate` (``mode="step"``,
    ``float64``) exactly whenever every current sum is exact (integer or dyadic
    weights, as in quantized networks): Brian2 adds a step's synaptic currents
    in its own order, so with inexact float sums a membrane landing within
    rounding of its threshold may fire one step apart.
    """
    if target not in TARGETS:
        raise SimulationError(f"network {network.name!r}: Brian2 target {target!r} is not one "
                              f"of {TARGETS}")
    b2 = b2 if b2 is not None else import_brian2()
    network.validate()
    check_decoders(network)
    clipped: dict[str, int] = {}
    trains, n_frames, framed = encode_inputs(network, inputs, out_of_range=out_of_range,
                                             clipped=clipped)
    saved = b2.prefs.codegen.target
    b2.prefs.codegen.target = target
    try:
        model = build_model(b2, network, trains, n_frames)
        model.net.run(network.n_steps * b2.ms, namespace={})
        act = read_activity(model, network, record_spikes)
    finally:
        b2.prefs.codegen.target = saved
    return SimResult(
        outputs=decode_outputs(network, act, framed),
        spike_counts={pid: int(c.sum()) for pid, c in act.counts.items()},
        synaptic_events=dict(act.synaptic_events),
        first_spike_steps={pid: first_steps(f, network.n_steps,
                                            (n_frames, *network.population[pid].dims))
                           for pid, f in act.first_spike.items()},
        spikes=None if act.rasters is None else {
            pid: r.reshape(n_frames, network.n_steps, *network.population[pid].dims)
            for pid, r in act.rasters.items()},
        mode=f"brian2-{target}", arithmetic="float64",
        n_steps=network.n_steps, n_frames=n_frames, clipped=clipped)
