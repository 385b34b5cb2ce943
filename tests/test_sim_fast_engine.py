"""The step engine against the plain per-step evaluation, bit for bit, on arbitrary floats.

The reference below is the step engine written the simple way: every step, every
population sums its projections' dense currents from zero (``dl.current``, delay
class by delay class), takes one ``neuron_step``, and counts synaptic events as
they happen; spike rasters are kept in full.  ``run_step`` (in-place neurons,
rows-only current additions, currents of encoder trains computed ahead in
batches, events counted once at the end, skipped no-op operations) must
reproduce every bit of it — membranes including the sign of zero — on random
networks with non-dyadic weights and parameters, negative zeros, every reset
rule, leaks, delays, recurrence, stencils, several projections into one target,
latency and rate codes, several frames, and in int64.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference import build_plan
from backends.reference.encoding import encode_inputs
from backends.reference.neuron import NeuronState, neuron_step
from backends.reference.step import run_step
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
    StencilProjection,
)


def reference_step(plan, trains, n_frames):
    """First spikes, counts, membranes and synaptic events, the plain way."""
    n_steps, pops = plan.network.n_steps, plan.populations
    raster = {p: np.zeros((n_steps, n_frames * pops[p].size), bool) for p in plan.order}
    states = {p: NeuronState.zeros((n_frames, pops[p].size), plan.integer) for p in plan.neurons}
    events = dict.fromkeys(plan.deliveries, 0)
    for t in range(n_steps):
        for pid in plan.order:
            if pid in trains:
                raster[pid][t, trains[pid].events_at(t)] = True
                continue
            params, current = plan.neurons[pid], 0
            for qid in plan.incoming[pid]:
                dl = plan.deliveries[qid]
                for k, d in enumerate(dl.delays):
                    ev = np.flatnonzero(raster[dl.source][t - d]) if t >= d else []
                    if len(ev):
                        events[qid] += dl.n_events(k, ev)
                        if params.input_on[t]:
                            current = current + dl.current(k, ev, n_frames)
            if not np.isscalar(current):
                current = current.reshape(n_frames, -1)
            spikes, states[pid] = neuron_step(states[pid], current, params, t)
            raster[pid][t] = spikes.reshape(-1)
    first = {p: np.where(r.any(0), r.argmax(0), -1) for p, r in raster.items()}
    counts = {p: r.sum(0) for p, r in raster.items()}
    return first, counts, {p: s.v for p, s in states.items()}, events, raster


def _number(rng: np.random.Generator, integer: bool, scale: float = 1.0) -> float:
    if integer:
        return float(rng.integers(-3, 6))
    pick = rng.random()
    return -0.0 if pick < 0.1 else 0.0 if pick < 0.2 else float(rng.normal(0.0, scale))


def random_network(seed: int) -> tuple[SpikingNetwork, np.ndarray, str]:
    rng = np.random.default_rng(seed)
    integer = rng.random() < 0.25
    n_steps = int(rng.integers(2, 24))
    once = rng.random() < 0.4  # all fire-once: the gathering path and encoder-train batches
    decays = [0.0, 1.0, 0.25, 3 / 4096] if integer else [0.0, 1.0, 0.3]
    src_dims = {"r": 2, "i0": 3} if rng.random() < 0.5 else {"i0": 3, "r": 2}
    pops = [Population(id="p0", shape=src_dims, source=True)]
    for layer in (1, 2):
        dims = {"r": 2, f"i{layer}": int(rng.integers(1, 4))}
        if rng.random() < 0.5:
            dims = dict(reversed(dims.items()))
        starts = sorted({0, int(rng.integers(1, n_steps + 1))})
        phases = tuple(Phase(start_step=s, bias=_number(rng, integer, 0.3),
                             input_on=bool(rng.random() < 0.8),
                             spiking_on=bool(rng.random() < 0.8)) for s in starts)
        params = NeuronParams(du=float(rng.choice(decays)), dv=float(rng.choice(decays)),
                              v_th=float(rng.integers(1, 6)) if integer
                              else abs(float(rng.normal(1.0, 0.5))) + 0.05,
                              reset="fire_once" if once else str(
                                  rng.choice(["value", "subtract", "fire_once"])),
                              v_reset=_number(rng, integer, 0.3), phases=phases)
        pops.append(Population(id=f"p{layer}", shape=dims, params=params))

    def weights(shape: tuple[int, ...]) -> np.ndarray:
        w = (rng.integers(-4, 6, size=shape).astype(float) if integer
             else rng.normal(0.0, 1.0, size=shape))
        w[rng.random(shape) < 0.2] = 0.0
        if not integer:
            w[rng.random(shape) < 0.1] = -0.0
        w.flat[0] = 1.0  # at least one synapse
        return w

    def matrix(pid: str, src: Population, tgt: Population, i: str, o: str, min_delay: int):
        w = weights((src.shape[i], tgt.shape[o]))
        delays = (rng.integers(min_delay, min_delay + 3, size=w.shape)
                  if min_delay or rng.random() < 0.4 else None)
        return MatrixProjection(id=pid, source=src.id, target=tgt.id, contract=(i,),
                                produce=(o,), weights=w, delays=delays)

    p0, p1, p2 = pops
    projs = [matrix("f1", p0, p1, "i0", "i1", 0), matrix("f2", p1, p2, "i1", "i2", 0)]
    if rng.random() < 0.5:  # a second projection into p2 in the same steps
        projs.append(matrix("skip", p0, p2, "i0", "i2", 0))
    if not once or rng.random() < 0.5:  # recurrence (the step engine only)
        n1 = p1.shape["i1"]
        kernel = weights((1 if n1 < 3 else 3,))
        projs.append(StencilProjection(id="lat", source="p1", target="p1", axes=("i1",),
                                       edge=(str(rng.choice(["wrap", "clip"])),), kernel=kernel,
                                       delays=rng.integers(1, 3, size=kernel.size)))
        projs.append(matrix("back", p2, p1, "i2", "i1", 1))
    code = (LatencyCode(t_max=int(rng.integers(1, n_steps + 1)), x_min=0.0, x_max=1.0)
            if rng.random() < 0.7 else RateCode(max_rate=0.5, phase=0.25))
    net = SpikingNetwork(name="fast", n_steps=n_steps, populations=pops, projections=projs,
                         encoders=[Encoder(port="x", population="p0", code=code)])
    x = rng.random((int(rng.integers(1, 4)), *p0.dims))
    return net, x, "int64" if integer else "float64"


def _bits(a: np.ndarray) -> np.ndarray:
    return a.view(np.int64) if a.dtype == np.float64 else a


@settings(max_examples=250, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_run_step_matches_the_plain_step_engine(seed: int) -> None:
    net, x, arithmetic = random_network(seed)
    plan = build_plan(net, arithmetic)
    trains, n_frames, _ = encode_inputs(net, {"x": x})
    with np.errstate(all="ignore"):
        first, counts, membrane, events, raster = reference_step(plan, trains, n_frames)
        # with rasters every source runs in the loop; without, latency trains read only
        # through currents computed ahead stay out of it
        runs = [run_step(plan, trains, n_frames, record=record) for record in (True, False)]
    for act in runs:
        for pid in plan.order:
            np.testing.assert_array_equal(act.first_spike[pid].ravel(), first[pid], err_msg=pid)
            np.testing.assert_array_equal(act.counts[pid].ravel(), counts[pid], err_msg=pid)
        for pid, v in membrane.items():
            np.testing.assert_array_equal(_bits(act.membrane[pid].ravel()), _bits(v.ravel()),
                                          err_msg=pid)
        assert act.synaptic_events == events
    for pid in plan.order:
        np.testing.assert_array_equal(
            runs[0].rasters[pid].transpose(1, 0, 2).reshape(raster[pid].shape), raster[pid],
            err_msg=pid)


def test_hand_worked_delayed_events_are_counted_only_when_delivered() -> None:
    """Three inputs, unit weights with delays (1, 0, 2), 3 steps.

    The latency code (t_max = 3 on [0, 1]) puts x = 1, 1/3, 2/3 at steps 0, 2, 1;
    arrivals are at 0 + 1 = 1, 2 + 0 = 2 and 1 + 2 = 3 ≥ 3 (never delivered): 2
    synaptic events.  b (IF: du = 1, v_th = 1.5, subtract) gets 1 at step 1
    (u = 1, v = 1) and 1 at step 2 (u = 0·1 + 1, v = 2): it fires at step 2 and
    keeps v = 2 - 1.5 = 0.5.
    """
    net = SpikingNetwork(
        name="d", n_steps=3,
        populations=[Population(id="a", shape={"i": 3}, source=True),
                     Population(id="b", shape={"o": 1},
                                params=NeuronParams(du=1.0, v_th=1.5, reset="subtract"))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                      produce=("o",), weights=np.ones((3, 1)),
                                      delays=np.array([[1], [0], [2]]))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=3, x_min=0.0, x_max=1.0))])
    plan = build_plan(net)
    trains, n_frames, _ = encode_inputs(net, {"x": np.array([1.0, 1 / 3, 2 / 3])})
    act = run_step(plan, trains, n_frames)
    assert act.first_spike["a"].tolist() == [[0, 2, 1]]
    assert act.synaptic_events == {"w": 2}
    assert act.first_spike["b"].tolist() == [[2]] and act.membrane["b"].tolist() == [[0.5]]
