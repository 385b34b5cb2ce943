r"""The closed-form engine: spike steps of fire-once feed-forward networks at matmul cost.

Eligible networks (:func:`closed_form_problems` is empty): every neuron
population has ``reset="fire_once"`` and the population graph is acyclic.
Then a neuron's ``u`` and ``v`` do not depend on its own spikes (fire-once
leaves ``v`` alone), so each population is solved once, in topological order,
from the spike steps of its sources, phase segment by phase segment.  With
arrival steps ``a_j = t_j + d_j`` of the synapses ``w_j`` and a segment
``[s_0, s_1)`` of ``L`` steps and bias ``b``:

*Silent* (input on, spiking off, ``d_v = 0``, ``d_u ∈ {0, 1}``) — no time loop:

.. math::

    d_u = 0:\quad u_1 &= u_0 + \textstyle\sum_j w_j, \qquad
    v_1 = v_0 + L\,(u_0 + b) + \textstyle\sum_j w_j\,(s_1 - a_j)\\
    d_u = 1:\quad u_1 &= I[s_1 - 1], \qquad v_1 = v_0 + L\,b + \textstyle\sum_j w_j

(sums over arrivals in the segment): two event-driven matrix products per
projection and delay.

*Gated* (``d_u = 1``, ``d_v = 0``, no bias, one excitatory synapse per neuron
and inhibitory stencils — the OS-CFAR neurons): one comparison per tap at the
excitatory arrival (:mod:`backends.reference.gate`).

*Charging* (input off, ``d_v = 0``): ``u = 0`` and ``v_0 + k\,b`` first reaches
``v_th`` at ``k = \lceil (v_{th} - v_0)/b \rceil`` (checked at ``k-1`` and ``k``).

*Driven* (anything else): the drive histogram ``D[t] = Σ_j w_j [a_j = t]`` of
the segment is one delivery over a ``(steps × frames)`` batch — the very
arithmetic of the step engine — and the recurrences run with the step engine's
operation order: ``np.cumsum`` (sequential) for ``d_u ∈ {0, 1}, d_v = 0``, else
:func:`~backends.reference.neuron.neuron_step` over the segment.  Long segments
are cut into blocks so the histogram stays under ``block_bytes``.

Exactness: the driven path is bit-identical to the step engine.  The silent
and charging paths reorder sums (``L·b`` for ``b + … + b``), so the two engines
give identical spike steps in int64 always, and in float64 whenever those sums
are exact — weights, thresholds, biases dyadic (e.g. multiples of ``2**-8``)
with magnitudes far below ``2**45``, as in quantized networks.  Outside that,
a membrane landing within rounding of the threshold may fire one step apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np

from backends.reference.delivery import Delivery
from backends.reference.encoding import Train
from backends.reference.gate import gate_inputs, is_gated_segment, solve_gated
from backends.reference.neuron import NeuronState, Segment, StepParams, neuron_step
from backends.reference.order import first_spike_steps, order_by_step
from backends.reference.plan import SimPlan
from backends.reference.result import Activity
from compiler.snn.network import SpikingNetwork

__all__ = ["closed_form_problems", "run_closed", "BLOCK_BYTES"]

#: Default cap on one driven block's drive histogram (bytes).
BLOCK_BYTES = 8 << 20


def closed_form_problems(network: SpikingNetwork) -> list[str]:
    """Why the closed form cannot simulate ``network`` (empty when it can).

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import NeuronParams, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4, populations=[
    ...     Population(id="a", shape={"i": 1}, params=NeuronParams(reset="subtract"))])
    >>> closed_form_problems(net)
    ["population 'a' has reset='subtract'; the closed form needs reset='fire_once'"]
    """
    problems = [f"population {p.id!r} has reset={p.params.reset!r}; the closed form needs "
                "reset='fire_once'"
                for p in network.populations if not p.source and p.params.reset != "fire_once"]
    g = nx.DiGraph([(p.source, p.target) for p in network.projections])
    if not nx.is_directed_acyclic_graph(g):
        edges = set(nx.find_cycle(g))
        on_cycle = [p.id for p in network.projections if (p.source, p.target) in edges]
        problems.append(f"projections {on_cycle} form a cycle through populations "
                        f"{[u for u, _ in edges]}; the closed form needs an acyclic "
                        "population graph")
    return problems


@dataclass(frozen=True)
class _Arrivals:
    """Spikes of one source through one delay class, sorted by arrival step."""

    delivery: Delivery
    k: int
    flat: np.ndarray
    arrive: np.ndarray

    def within(self, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = np.searchsorted(self.arrive, (start, stop))
        return self.flat[lo:hi], self.arrive[lo:hi]


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
        Cap on one drive histogram; longer driven segments are cut into blocks.

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
        if pid in first:  # fire-once neurons: at most one spike each
            counts[pid] = (first[pid] >= 0).astype(np.int64).reshape(n_frames, -1)
        else:
            counts[pid] = np.bincount(flat, minlength=n).astype(np.int64).reshape(n_frames, -1)
        first[pid] = (first[pid] if pid in first else first_spike_steps(flat, step, n)
                      ).reshape(n_frames, -1)
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
    """Spike events ``(flat, step)`` by step, end membranes and first spike steps of ``pid``."""
    params = plan.neurons[pid]
    n_steps = plan.network.n_steps
    arrivals = []
    for qid in plan.incoming[pid]:
        dl = plan.deliveries[qid]
        flat, step = spikes[dl.source]
        for k, d in enumerate(dl.delays):
            stop = _arriving(step, d, n_steps)
            arrivals.append(_Arrivals(dl, k, flat[:stop], step[:stop] + d if d else step[:stop]))
    pop = plan.populations[pid]
    n = n_frames * pop.size
    dtype = np.int64 if plan.integer else np.float64
    u, v, first = np.zeros(n, dtype), np.zeros(n, dtype), np.full(n, -1, np.int64)
    simple = params.dv == 0.0 and params.du in (0.0, 1.0)
    block = max(1, block_bytes // (3 * 8 * n))
    for i, seg in enumerate(params.segments):
        if not seg.input_on and params.dv == 0.0:
            u, v = _charge(v, first, seg, params)
        elif seg.input_on and not seg.spiking_on and simple:
            # the end current u matters only if a later segment takes input (else it is reset)
            need_u = any(s.input_on for s in params.segments[i + 1:])
            u, v = _silent(u, v, seg, params, arrivals, n_frames, pop.dims, need_u=need_u)
        elif (is_gated_segment(seg, params) and (gates := gate_inputs(plan, pid)) is not None
              and (end := solve_gated(plan, pid, gates, seg, params, v, first, spikes, n_frames,
                                      any(s.input_on for s in params.segments[i + 1:])))
              is not None):
            u, v = end
        else:
            for s0 in range(seg.start, seg.stop, block):
                part = seg._replace(start=s0, stop=min(s0 + block, seg.stop))
                u, v = _driven(u, v, first, part, params, arrivals, n_frames, pop.dims)
    flat = np.flatnonzero(first >= 0)
    order = order_by_step(first[flat], n_steps)  # flat is ascending: ties stay by neuron
    return (flat[order], first[flat][order]), v.reshape(n_frames, -1), first


def _charge(
    v: np.ndarray, first: np.ndarray, seg: Segment, params: StepParams
) -> tuple[np.ndarray, np.ndarray]:
    """Input off, no leak: ``v`` grows by ``b`` per step; the first crossing is analytic.

    Only neurons that have not fired and end the segment at or above threshold
    can cross in it (``v + k b`` is monotone in ``k``, rounding included), so the
    step arithmetic runs on those candidates alone.
    """
    n, b = seg.stop - seg.start, seg.bias
    if b == 0 and not seg.spiking_on:
        return np.zeros_like(v), v
    end = v + n * b
    if seg.spiking_on:
        top = end if b > 0 else np.maximum(v + b, end)
        idle = np.flatnonzero((top >= params.v_th) & (first < 0))
        w = v[idle]
        if b > 0:
            gap = params.v_th - w
            k = -((-gap) // b) if params.integer else np.ceil(gap / b)
            k = np.clip(k, 1, n + 1).astype(np.int64)
            k = np.where((k > 1) & (w + (k - 1) * b >= params.v_th), k - 1, k)
            k = np.where(w + k * b < params.v_th, k + 1, k)
        else:
            k = np.where(w + b >= params.v_th, 1, n + 1)
        hit = k <= n
        first[idle[hit]] = seg.start + k[hit] - 1
    return np.zeros_like(v), end


def _silent(
    u: np.ndarray, v: np.ndarray, seg: Segment, params: StepParams, arrivals: list,
    n_frames: int, dims: tuple[int, ...], need_u: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Input on, spiking off, ``dv = 0``, ``du ∈ {0, 1}``: end state from arrival features.

    With ``du = 0`` and ``need_u`` False the end current (``u + Σ w``) is not
    computed: no later segment reads it (the caller checked), saving one product.
    """
    s0, s1, b = seg.start, seg.stop, seg.bias
    total = np.zeros((n_frames, *dims), u.dtype)
    second = np.zeros_like(total)
    for arr in arrivals:
        flat, arrive = arr.within(s0, s1)
        if not flat.size:
            continue
        # unit weights route the silent stage's bulk delivery through the BLAS path (event
        # order is immaterial here: the silent path is exact only where every sum is exact)
        if need_u or params.du != 0.0:
            total += arr.delivery.current(arr.k, flat, n_frames, values=np.ones(flat.size))
        if params.du == 0.0:
            second += arr.delivery.current(arr.k, flat, n_frames, values=s1 - arrive)
        else:
            last = arrive == s1 - 1
            if last.any():
                second += arr.delivery.current(arr.k, flat[last], n_frames)
    total, second = total.reshape(u.shape), second.reshape(u.shape)
    if params.du == 0.0 and s0 == 0:  # the first segment: u = v = 0, skip the zero terms
        return total, second if b == 0 else second + s1 * b
    if params.du == 0.0:
        return u + total, v + (s1 - s0) * (u + b) + second
    return second, v + (s1 - s0) * b + total


def _driven(
    u: np.ndarray, v: np.ndarray, first: np.ndarray, seg: Segment, params: StepParams,
    arrivals: list, n_frames: int, dims: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Any segment: drive histogram by delivery, then the step engine's recurrences."""
    s0, n_t = seg.start, seg.stop - seg.start
    if not seg.input_on:
        return _recur(u, v, first, seg, params, None)
    drive = np.zeros((n_t * n_frames, *dims), u.dtype)
    for arr in arrivals:
        flat, arrive = arr.within(s0, seg.stop)
        if not flat.size:
            continue
        src_size = arr.delivery.src_size
        f, i = np.divmod(flat, src_size)
        batch = np.sort(((arrive - s0) * n_frames + f) * src_size + i)
        drive += arr.delivery.current(arr.k, batch, n_t * n_frames)
    drive = drive.reshape(n_t, -1)
    if params.dv == 0.0 and params.du in (0.0, 1.0):
        cur = np.cumsum(np.vstack([u[None], drive]), axis=0)[1:] if params.du == 0.0 else drive
        vs = np.cumsum(np.vstack([v[None], cur + seg.bias]), axis=0)[1:]
        if seg.spiking_on:
            cross = vs >= params.v_th
            hit = cross.any(axis=0) & (first < 0)
            first[hit] = s0 + cross.argmax(axis=0)[hit]
        return cur[-1].copy(), vs[-1].copy()
    return _recur(u, v, first, seg, params, drive)


def _recur(
    u: np.ndarray, v: np.ndarray, first: np.ndarray, seg: Segment, params: StepParams,
    drive: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The step engine's own update over the segment (general decays)."""
    state = NeuronState(u, v, first >= 0)
    for i, t in enumerate(range(seg.start, seg.stop)):
        fired, state = neuron_step(state, 0 if drive is None else drive[i], params, t)
        first[fired] = t
    return state.u, state.v
