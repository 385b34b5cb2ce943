r"""The step engine: one loop over time steps, everything inside vectorized over frames × neurons.

Per step ``t``, for each population in ``plan.order`` (zero-delay edges run
source before target):

1. a source emits its train's spikes of step ``t``;
2. a neuron population sums the currents of its incoming projections — for
   each delay class ``d``, the source's spikes of step ``t - d`` read from a
   ring buffer of the last ``history`` steps (event lists, not rasters) — then
   takes one :func:`~backends.reference.neuron.neuron_step`.

Where a population's input phase is off its currents are not computed (they
would be dropped), but the synaptic events are still counted: a chip routes
them anyway.
"""

from __future__ import annotations

import numpy as np

from backends.reference.encoding import Train
from backends.reference.neuron import NeuronState, neuron_step
from backends.reference.plan import SimPlan
from backends.reference.result import Activity

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
    """
    n_steps = plan.network.n_steps
    pops = plan.populations
    size = {pid: pops[pid].size for pid in plan.order}
    states = {pid: NeuronState.zeros((n_frames, size[pid]), plan.integer) for pid in plan.neurons}
    empty = np.zeros(0, np.int64)
    ring = {pid: [empty] * plan.history[pid] for pid in plan.order}
    first = {pid: np.full(n_frames * size[pid], -1, np.int64) for pid in plan.order}
    counts = {pid: np.zeros(n_frames * size[pid], np.int64) for pid in plan.order}
    events = dict.fromkeys(plan.deliveries, 0)
    rasters = ({pid: np.zeros((n_frames, n_steps, size[pid]), bool) for pid in plan.order}
               if record else None)

    for t in range(n_steps):
        for pid in plan.order:
            if pid in trains:
                fired = trains[pid].events_at(t)
            else:
                params = plan.neurons[pid]
                take = bool(params.input_on[t])
                current = 0  # stays a scalar until some projection delivers
                for qid in plan.incoming[pid]:
                    dl = plan.deliveries[qid]
                    for k, d in enumerate(dl.delays):
                        if t < d:
                            continue
                        ev = ring[dl.source][(t - d) % plan.history[dl.source]]
                        if ev.size:
                            events[qid] += dl.n_events(k, ev)
                            if take:
                                current = current + dl.current(k, ev, n_frames)
                if take and not np.isscalar(current):
                    current = current.reshape(n_frames, size[pid])
                spikes, states[pid] = neuron_step(states[pid], current, params, t)
                fired = np.flatnonzero(spikes)
            ring[pid][t % plan.history[pid]] = fired
            if fired.size:
                counts[pid][fired] += 1
                new = fired[first[pid][fired] < 0]
                first[pid][new] = t
                if rasters is not None:
                    f, n = np.divmod(fired, size[pid])
                    rasters[pid][f, t, n] = True

    def framed(a: np.ndarray) -> np.ndarray:
        return a.reshape(n_frames, -1)

    return Activity(
        first_spike={k: framed(v) for k, v in first.items()},
        counts={k: framed(v) for k, v in counts.items()},
        membrane={k: s.v for k, s in states.items()},
        synaptic_events=events,
        rasters=rasters,
    )
