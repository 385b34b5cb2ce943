r"""The closed-form engine: spike steps of fire-once feed-forward networks at matmul cost.

Eligible networks (:func:`closed_form_problems` is empty): every neuron
population has ``reset="fire_once"`` and the population graph is acyclic.
Then a neuron's ``u`` and ``v`` do not depend on its own spikes (fire-once
leaves ``v`` alone), so each population is solved once, in topological order,
from the spike steps of its sources, phase span by phase span, each by
the cheapest exact rule (:mod:`backends.reference.spans`): *silent*
(input on, spiking off: arrival features, no time loop), *gated* (the OS-CFAR
neurons: one comparison per tap, :mod:`backends.reference.gate`), *charging*
(input off: the analytic crossing), else *driven* (the step engine's own
arithmetic over a drive histogram).

Exactness: the driven path is bit-identical to the step engine.  The silent,
gated and charging paths reorder sums (``L·b`` for ``b + … + b``), so the two
engines give identical spike steps in int64 always, and in float64 whenever
those sums are exact — weights, thresholds, biases dyadic (e.g. multiples of
``2**-8``) with magnitudes far below ``2**45``, as in quantized networks.
Outside that, a membrane landing within rounding of the threshold may fire one
step apart.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from backends.reference.encoding import Train
from backends.reference.gate import is_gated_span, solve_gated
from backends.reference.order import first_spike_steps, order_by_step
from backends.reference.plan import SimPlan, closed_form_problems
from backends.reference.resonator import ResonatorStepParams, solve_resonator
from backends.reference.result import Activity
from backends.reference.spans import Arrivals, charge, drive, driven, silent

__all__ = ["closed_form_problems", "run_closed", "BLOCK_BYTES"]

#: Default cap on one driven block's drive histogram (bytes).
BLOCK_BYTES = 8 << 20


def run_closed(
    plan: SimPlan,
    trains: dict[str, Train],
    n_frames: int,
    record: bool = False,
    block_bytes: int = BLOCK_BYTES,
) -> Activity:
    """Solve an eligible network population by population.

    Parameters
    ----------
    plan : SimPlan
        The prepared network (eligibility checked by the caller).
    trains : dict
        Spike train per source population.
    n_frames : int
        Frames in the batch.
    record : bool
        Build spike rasters from the spike steps.
    block_bytes : int
        Cap on one drive histogram; longer driven spans are cut into blocks.

    Returns
    -------
    Activity

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
    >>> act = run_closed(build_plan(net), trains, n_frames)
    >>> act.first_spike["b"].tolist(), act.membrane["b"].tolist()
    ([[2]], [[10.0]])
    """
    net, n_steps = plan.network, plan.network.n_steps
    g = nx.DiGraph([(p.source, p.target) for p in net.projections])
    g.add_nodes_from(plan.populations)
    spikes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    membrane, first = {}, {}
    for pid in nx.lexicographical_topological_sort(g):
        if pid in trains:
            spikes[pid] = trains[pid].all_events()
        else:
            spikes[pid], membrane[pid], first[pid] = _solve(plan, pid, spikes, n_frames,
                                                             block_bytes)
    events = {}
    for qid, dl in plan.deliveries.items():
        flat, step = spikes[dl.source]
        events[qid] = sum(dl.n_events(k, flat[:_arriving(step, d, n_steps)])
                          for k, d in enumerate(dl.delays))
    counts, rasters = {}, {} if record else None
    for pid, pop in plan.populations.items():
        flat, step = spikes[pid]
        n = n_frames * pop.size
        if pid not in first and getattr(trains[pid], "at_most_once", False):
            first[pid] = np.full(n, -1, np.int64)  # a latency train: one spike at most
            first[pid][flat] = step
        if pid in first:  # fire-once neurons and latency trains: at most one spike each
            counts[pid] = (first[pid] >= 0).astype(np.int64).reshape(n_frames, -1)
        else:
            counts[pid] = np.bincount(flat, minlength=n).astype(np.int64).reshape(n_frames, -1)
            first[pid] = first_spike_steps(flat, step, n)
        first[pid] = first[pid].reshape(n_frames, -1)
        if rasters is not None:
            rasters[pid] = np.zeros((n_frames, n_steps, pop.size), bool)
            f, i = np.divmod(flat, pop.size)
            rasters[pid][f, step, i] = True
    return Activity(first, counts, membrane, events, rasters)


def _arriving(step: np.ndarray, delay: int, n_steps: int) -> int:
    """How many of the step-sorted spikes arrive within the window through ``delay``."""
    return int(np.searchsorted(step, n_steps - delay))


def _solve(
    plan: SimPlan, pid: str, spikes: dict, n_frames: int, block_bytes: int
) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray, np.ndarray]:
    """Spike events ``(flat, step)``, end membranes and first spike steps of ``pid``.

    The events are ordered by step (ties by neuron) when a projection reads them.
    """
    params = plan.neurons[pid]
    n_steps = plan.network.n_steps
    arrivals = []
    for qid in plan.incoming[pid]:
        dl = plan.deliveries[qid]
        flat, step = spikes[dl.source]
        for k, d in enumerate(dl.delays):
            stop = _arriving(step, d, n_steps)
            arrivals.append(Arrivals(dl, k, flat[:stop], step[:stop] + d if d else step[:stop]))
    pop = plan.populations[pid]
    n = n_frames * pop.size
    dtype = np.int64 if plan.integer else np.float64
    u, v, first = np.zeros(n, dtype), np.zeros(n, dtype), np.full(n, -1, np.int64)
    if isinstance(params, ResonatorStepParams):
        v = solve_resonator(params, lambda s0, s1: drive(arrivals, s0, s1, n_frames, pop.dims,
                                                         dtype), n, first, charge)
    else:
        v = _solve_neurons(plan, pid, params, arrivals, spikes, n_frames, block_bytes, u, v,
                           first)
    flat = np.flatnonzero(first >= 0)
    if not any(q.source == pid for q in plan.network.projections):
        return (flat, first[flat]), v.reshape(n_frames, -1), first  # nobody reads them by step
    order = order_by_step(first[flat], n_steps)  # flat is ascending: ties stay by neuron
    return (flat[order], first[flat][order]), v.reshape(n_frames, -1), first


def _solve_neurons(plan: SimPlan, pid: str, params, arrivals: list, spikes: dict,
                   n_frames: int, block_bytes: int, u: np.ndarray, v: np.ndarray,
                   first: np.ndarray) -> np.ndarray:
    """End membranes of an IF/LIF population, span by span; fills ``first``."""
    pop = plan.populations[pid]
    n = n_frames * pop.size
    simple = params.dv == 0.0 and params.du in (0.0, 1.0)
    block = max(1, block_bytes // (3 * 8 * n))
    for i, seg in enumerate(params.spans):
        if not seg.input_on and params.dv == 0.0:
            u, v = charge(v, first, seg, params)
        elif seg.input_on and not seg.spiking_on and simple:
            # the end current u matters only if a later span takes input (else it is reset)
            need_u = any(s.input_on for s in params.spans[i + 1:])
            u, v = silent(u, v, seg, params, arrivals, n_frames, pop.dims, need_u=need_u)
        elif (is_gated_span(seg, params) and (gates := plan.gates.get(pid)) is not None
              and (end := solve_gated(plan, pid, gates, seg, params, v, first, spikes, n_frames,
                                      any(s.input_on for s in params.spans[i + 1:])))
              is not None):
            u, v = end
        else:
            for s0 in range(seg.start, seg.stop, block):
                part = seg._replace(start=s0, stop=min(s0 + block, seg.stop))
                u, v = driven(u, v, first, part, params, arrivals, n_frames, pop.dims)
    return v


