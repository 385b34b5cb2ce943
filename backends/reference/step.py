r"""The step engine: one loop over time steps, everything inside vectorized over frames × neurons.

Per step ``t``, for each population in ``plan.order`` (zero-delay edges run
source before target):

1. a source emits its train's spikes of step ``t``;
2. a neuron population gathers its contributions — for each incoming projection
   and delay class ``d``, the source's spikes of step ``t - d`` read from a ring
   buffer of the last ``history`` steps (event lists, not rasters) — and takes
   one in-place step (:class:`~backends.reference.live_neurons.LiveNeurons`, the
   arithmetic of :func:`~backends.reference.neuron.neuron_step`), the currents
   added into its state by :func:`~backends.reference.delivery.add_current`.
   Projections fed by an encoder's latency train (known before the loop) take
   their currents from :class:`~backends.reference.delivery.TrainCurrents`,
   computed many steps per batch with the same per-row arithmetic.

Where a population's input phase is off its currents are not computed (they
would be dropped).  Synaptic events — spikes delivered within the frame times
the synapses each reaches, counted whether or not the target's input is on — are
counted once after the loop: every spike's synapses
(:func:`~backends.reference.delivery.synapses_per_source`) minus those of the
spikes of the last ``d`` steps, still in the ring buffer, which arrive too late.

Fire-once populations and latency trains spike at most once per neuron: only
their first spike step is kept during the loop, their counts follow from it.  A
latency train whose every reader takes its currents ahead (and no raster is
recorded) does not enter the loop at all: its first spikes are its spike steps.

Every step performs, element by element, the floating-point operations of
:func:`~backends.reference.neuron.neuron_step` and of the deliveries' ``current``
(``tests/test_sim_fast_engine.py`` checks every bit, signed zeros included,
against the plain per-step evaluation); only operations that cannot change a bit
are left out (:class:`~backends.reference.live_neurons.LiveNeurons`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from backends.reference.delivery import (
    TRAIN_CURRENTS,
    Delivery,
    TrainCurrents,
    add_current,
    synapses_per_source,
)
from backends.reference.live_neurons import LiveNeurons
from backends.reference.plan import SimPlan
from backends.reference.resonator import LiveResonators, ResonatorStepParams
from backends.reference.result import Activity
from backends.reference.trains import Train

__all__ = ["run_step"]


def run_step(
    plan: SimPlan, trains: dict[str, Train], n_frames: int, record: bool = False
) -> Activity:
    """Simulate every step of ``n_frames`` frames.

    Parameters
    ----------
    plan : SimPlan
        The prepared network.
    trains : dict
        Spike train per source population (from :func:`encode_inputs`).
    n_frames : int
        Frames in the batch.
    record : bool
        Keep full spike rasters.

    Returns
    -------
    Activity
        First spikes, counts, final membranes, synaptic events (and rasters).

    Examples
    --------
    >>> import numpy as np
    >>> from backends.reference import build_plan
    >>> from backends.reference.encoding import encode_inputs
    >>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, NeuronParams,
    ...                           Population, SpikingNetwork)
    >>> net = SpikingNetwork(name="n", n_steps=6,
    ...     populations=[Population(id="a", shape={"i": 2}, source=True),
    ...                  Population(id="b", shape={"o": 1},
    ...                             params=NeuronParams(du=0.0, v_th=3.0, reset="fire_once"))],
    ...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
    ...                                   produce=("o",), weights=np.ones((2, 1)))],
    ...     encoders=[Encoder(port="x", population="a",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
    >>> trains, n_frames, framed = encode_inputs(net, {"x": np.array([1.0, 0.5])})
    >>> act = run_step(build_plan(net), trains, n_frames)
    >>> act.first_spike["a"].tolist(), act.first_spike["b"].tolist(), act.membrane["b"].tolist()
    ([[0, 2]], [[2]], [[10.0]])
    >>> act.counts["b"].tolist(), act.synaptic_events
    ([[1]], {'w': 2})
    """
    n_steps = plan.network.n_steps
    pops = plan.populations
    size = {pid: pops[pid].size for pid in plan.order}
    live = {pid: LiveResonators(plan.neurons[pid], n_frames * size[pid])
            if isinstance(plan.neurons[pid], ResonatorStepParams)
            else LiveNeurons(plan.neurons[pid], n_frames * size[pid], plan.state_limit)
            for pid in plan.neurons}
    empty = np.zeros(0, np.int64)
    ring = {pid: [empty] * plan.history[pid] for pid in plan.order}
    feeds = {pid: [_feed(plan, trains, ring, dl, k, d, n_frames)
                   for qid in plan.incoming[pid]
                   for dl in (plan.deliveries[qid],) for k, d in enumerate(dl.delays)]
             for pid in plan.neurons}
    # trains read by no feed step by step (all their currents computed ahead) stay out of the loop
    read_live = {f.delivery.source for fs in feeds.values() for f in fs if f.ahead is None}
    offline = {pid for pid, tr in trains.items()
               if tr.at_most_once and not record and pid not in read_live}
    once = {pid: (pid in trains and trains[pid].at_most_once)
            or (pid in plan.neurons and plan.neurons[pid].reset == "fire_once")
            for pid in plan.order}
    first = {pid: np.full(n_frames * size[pid], -1, np.int64) for pid in plan.order}
    counts = {pid: np.zeros(n_frames * size[pid], np.int64) for pid in plan.order
              if not once[pid]}
    rasters = ({pid: np.zeros((n_frames, n_steps, size[pid]), bool) for pid in plan.order}
               if record else None)

    def add(contribution: tuple, out: np.ndarray) -> None:
        contribution[0](*contribution[1:], out)

    steps = [(pid, trains.get(pid), live.get(pid), feeds.get(pid), ring[pid], plan.history[pid],
              first[pid], counts.get(pid)) for pid in plan.order if pid not in offline]
    for t in range(n_steps):
        for pid, train, neurons, inputs, own_ring, own_history, fst, cnt in steps:
            if train is not None:
                fired = train.events_at(t)
            else:
                arrivals = []
                if neurons.takes_input(t):
                    for f in inputs:
                        if f.ahead is not None:
                            rows = f.ahead.at(t)
                            if rows is not None:
                                arrivals.append((f.ahead.add_rows, *rows))
                        elif t >= f.delay:
                            ev = f.ring[(t - f.delay) % f.history]
                            if ev.size:
                                arrivals.append((add_current, f.delivery, f.k, ev, n_frames))
                fired = neurons.step(t, arrivals, add)
            own_ring[t % own_history] = fired
            if fired.size:
                if cnt is None:
                    fst[fired] = t
                else:
                    cnt[fired] += 1
                    new = fired[fst[fired] < 0]
                    fst[new] = t
                if rasters is not None:
                    f, n = np.divmod(fired, size[pid])
                    rasters[pid][f, t, n] = True

    for pid in offline:
        flat, step = trains[pid].all_events()
        first[pid][flat] = step
    for pid in plan.order:
        if once[pid]:
            counts[pid] = (first[pid] >= 0).astype(np.int64)
    events = {qid: _synaptic_events(dl, trains.get(dl.source), counts[dl.source], ring[dl.source],
                                    n_frames, n_steps)
              for qid, dl in plan.deliveries.items()}

    def framed(a: np.ndarray) -> np.ndarray:
        return a.reshape(n_frames, -1)

    return Activity(
        first_spike={k: framed(v) for k, v in first.items()},
        counts={k: framed(counts[k]) for k in plan.order},
        membrane={k: framed(s.v) for k, s in live.items()},
        synaptic_events=events,
        rasters=rasters,
        overflow={k: s.overflow for k, s in live.items() if getattr(s, "overflow", 0)},
    )


class _Feed(NamedTuple):
    """One delay class of one incoming projection, as the loop reads it."""

    delivery: Delivery
    k: int
    delay: int
    ring: list  # the source's ring buffer of event lists
    history: int  # its length
    ahead: TrainCurrents | None  # currents computed ahead (encoder trains)


def _feed(plan: SimPlan, trains: dict[str, Train], ring: dict, dl: Delivery, k: int, d: int,
          n_frames: int) -> _Feed:
    """The feed of delay class ``k``; currents ahead when an encoder's latency train feeds it."""
    train = trains.get(dl.source)
    ahead = None
    if (train is not None and train.at_most_once
            and TRAIN_CURRENTS.get(type(dl), lambda _: False)(dl)):
        ahead = TrainCurrents(dl, k, d, *train.all_events(), n_frames, plan.network.n_steps,
                              paired=True)
    return _Feed(dl, k, d, ring[dl.source], plan.history[dl.source], ahead)


def _synaptic_events(dl: Delivery, train: Train | None, counts: np.ndarray, ring: list,
                     n_frames: int, n_steps: int) -> int:
    """Spikes of ``dl``'s source delivered before ``n_steps``, times their synapses."""
    total = 0
    for k, d in enumerate(dl.delays):
        synapses = synapses_per_source(dl, k)
        if train is not None and train.at_most_once:  # every spike known: count directly
            flat, step = train.all_events()
            total += int(synapses[flat[step + d < n_steps] % synapses.size].sum())
            continue
        total += int(counts.reshape(n_frames, -1).sum(axis=0) @ synapses)
        # the spikes of the last d steps (still in the ring) arrive at or after n_steps
        total -= sum(dl.n_events(k, ring[s % len(ring)]) for s in range(max(0, n_steps - d),
                                                                         n_steps))
    return total
