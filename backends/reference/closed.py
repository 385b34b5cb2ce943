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

from backends.reference.delivery import synapses_per_source
from backends.reference.fired import Fired
from backends.reference.gate import is_gated_span, solve_gated
from backends.reference.order import first_spike_steps
from backends.reference.plan import SimPlan, closed_form_problems
from backends.reference.resonator import ResonatorStepParams
from backends.reference.resonator_closed import solve_resonators
from backends.reference.result import Activity, LazyArrays
from backends.reference.spans import Arrivals, charge, driven, silent
from backends.reference.trains import StreamTrain, Train

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
    spikes: dict[str, Fired] = {}
    membrane, first = {}, {}
    for pid in nx.lexicographical_topological_sort(g):
        if pid in trains:
            spikes[pid] = _fired_of_train(trains[pid], n_steps)
        else:
            first[pid], membrane[pid] = _solve(plan, pid, spikes, n_frames, block_bytes)
            spikes[pid] = Fired.of_first(first[pid], n_steps)
    events = {qid: sum(_synaptic_events(dl, k, d, spikes[dl.source])
                       for k, d in enumerate(dl.delays)) for qid, dl in plan.deliveries.items()}
    counts, totals, rasters = {}, {}, {} if record else None
    for pid, pop in plan.populations.items():
        fired, n = spikes[pid], n_frames * pop.size
        if rasters is not None:
            flat, step = fired.events()
            rasters[pid] = np.zeros((n_frames, n_steps, pop.size), bool)
            f, i = np.divmod(flat, pop.size)
            rasters[pid][f, step, i] = True
        if fired.first is not None:  # fire-once neurons and latency trains: one spike at most
            first[pid] = fired.first
            spans = getattr(plan.neurons.get(pid), "spans", None)
            counts[pid] = (np.zeros((n_frames, pop.size), bool)  # never spiking: none
                           if spans is not None and not any(s.spiking_on for s in spans)
                           else fired.fired_mask.reshape(n_frames, -1))  # 0/1: no int64 copy
        elif fired.stream is not None:  # stream levels: the total now, per neuron on demand
            totals[pid] = fired.stream.total(n_steps)
            counts[pid] = lambda f=fired, n=n_frames: f.counts_before(f.n_steps).reshape(n, -1)
            first[pid] = lambda f=fired, n=n_frames: f.first_steps().reshape(n, -1)
            continue
        elif fired.has_raster:  # stream trains as bit planes, no event lists
            counts[pid] = fired.counts_before(n_steps).reshape(n_frames, -1)
            first[pid] = fired.first_steps()
        else:
            flat, step = fired.events()
            counts[pid] = np.bincount(flat, minlength=n).astype(np.int64).reshape(n_frames, -1)
            first[pid] = first_spike_steps(flat, step, n)
        first[pid] = first[pid].reshape(n_frames, -1)
    return Activity(LazyArrays(first), LazyArrays(counts), membrane, events, rasters,
                    totals=totals)


def _fired_of_train(train: Train, n_steps: int) -> Fired:
    """A source's spikes: the first-spike steps of an at-most-once train that has them
    (:class:`~backends.reference.encoding.LatencyTrain`), the raster of a stream train
    (:class:`~backends.reference.encoding.StreamTrain`), else its events."""
    first = getattr(train, "first", None) if train.at_most_once else None
    if first is not None:  # a latency train carries its first-spike steps
        return Fired.of_first(first, n_steps)
    if isinstance(train, StreamTrain):
        return Fired.of_stream(train.stream, n_steps)
    return Fired.of_events(*train.all_events(), n_steps)


def _synaptic_events(dl, k: int, delay: int, fired: Fired) -> int:
    """Synaptic events of delay class ``k``: the spikes arriving within the window."""
    if fired.first is None and fired.has_raster:  # spikes per source, then synapses
        return fired.synaptic_events(fired.n_steps - delay, synapses_per_source(dl, k))
    if fired.first is None:
        flat, step = fired.events()
        return dl.n_events(k, flat[:int(np.searchsorted(step, fired.n_steps - delay))])
    arriving = fired.arriving(delay, fired.n_steps)
    groups = getattr(dl, "source_synapse_groups", None)  # matrix deliveries: few fan-outs
    if groups is not None and groups[k] is not None:
        rows = arriving.reshape(-1, dl.src_size)
        return sum(count * int(np.count_nonzero(rows & mask)) for count, mask in groups[k])
    per_source = synapses_per_source(dl, k)
    arriving = arriving.reshape(-1, per_source.size)
    return int(np.sum(arriving @ per_source))  # bool @ int64: exact, no masked reduction


def _solve(
    plan: SimPlan, pid: str, spikes: dict[str, Fired], n_frames: int, block_bytes: int
) -> tuple[np.ndarray, np.ndarray]:
    """First spike steps (flat, ``-1``: none) and end membranes of ``pid``."""
    params = plan.neurons[pid]
    n_steps = plan.network.n_steps
    arrivals = [Arrivals(plan.deliveries[qid], k, d, spikes[plan.deliveries[qid].source],
                         n_steps)
                for qid in plan.incoming[pid] for k, d in enumerate(plan.deliveries[qid].delays)]
    pop = plan.populations[pid]
    n = n_frames * pop.size
    dtype = np.int64 if plan.integer else np.float64
    # the start state: read-only zeros (the span solvers make new arrays, or charge writes
    # into a v of its own), not two population-sized arrays per frame
    u = v = np.broadcast_to(np.zeros(1, dtype), (n,))
    first = np.full(n, -1, np.int64)
    if isinstance(params, ResonatorStepParams):
        v = solve_resonators(plan, pid, arrivals, n_frames, first)
    else:
        v = _solve_neurons(plan, pid, params, arrivals, spikes, n_frames, block_bytes, u, v,
                           first)
    return first, v.reshape(n_frames, -1)


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
            # v is this solver's own once a span has made it (not the zeros it starts from)
            u, v = charge(v, first, seg, params, in_place=v.flags.writeable)
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


