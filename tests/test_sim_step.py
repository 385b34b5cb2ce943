"""The step engine against a naive simulator written plainly in this file.

The naive simulator expands every projection into a dense ``(source neurons,
target neurons)`` matrix per delay by explicit loops over neuron coordinates
(axes matched by name), keeps full spike rasters, and writes the neuron update
of ``compiler.snn.neurons`` out by hand.  Random networks here use every reset
rule, recurrent projections (self-loops and backward edges with delays ≥ 1)
and dyadic numbers, so both simulators compute exactly and must agree to the bit.
"""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference import closed_form_problems, simulate
from compiler.snn import (
    Decoder,
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


def dense_matrices(proj, src: Population, tgt: Population) -> dict[int, np.ndarray]:
    """``{d: M_d}`` with ``I_target = Σ_d s_source[t - d] @ M_d``, by brute force."""
    out: dict[int, np.ndarray] = {}
    src_idx = list(itertools.product(*(range(n) for n in src.dims)))
    tgt_idx = list(itertools.product(*(range(n) for n in tgt.dims)))
    for a, xs in enumerate(src_idx):
        x = dict(zip(src.axes, xs, strict=True))
        for b, ys in enumerate(tgt_idx):
            y = dict(zip(tgt.axes, ys, strict=True))
            for w, d in _synapses(proj, src, tgt, x, y):
                out.setdefault(d, np.zeros((len(src_idx), len(tgt_idx))))[a, b] += w
    return out


def _synapses(proj, src, tgt, x, y):
    if proj.kind == "matrix":
        if any(x[a] != y[a] for a in x if a not in proj.contract):
            return []
        row = np.ravel_multi_index([x[a] for a in proj.contract],
                                   [src.shape[a] for a in proj.contract])
        col = np.ravel_multi_index([y[a] for a in proj.produce],
                                   [tgt.shape[a] for a in proj.produce])
        w = proj.weights[row, col]
        d = 0 if proj.delays is None else int(proj.delays[row, col])
        return [(w, d)] if w else []
    if any(x[a] != y[a] for a in x if a not in proj.axes):
        return []
    found = []
    for k in itertools.product(*(range(n) for n in proj.kernel.shape)):
        ok = True
        for axis, ki, rad, edge in zip(proj.axes, k, proj.radius, proj.edge, strict=True):
            xi = y[axis] + ki - rad
            xi = xi % src.shape[axis] if edge == "wrap" else xi
            ok &= xi == x[axis]
        if ok and proj.kernel[k]:
            found.append((proj.kernel[k], 0 if proj.delays is None else int(proj.delays[k])))
    return found


def naive_simulate(net: SpikingNetwork, x: np.ndarray):
    """First spike steps and final membranes per population, by the book."""
    pops, (enc,) = net.population, net.encoders
    frames, n_steps = x.shape[0], net.n_steps
    raster = {p.id: np.zeros((n_steps, frames, p.size), bool) for p in net.populations}
    vals = x.reshape(frames, -1)
    mats = {q.id: dense_matrices(q, pops[q.source], pops[q.target]) for q in net.projections}
    u = {p.id: np.zeros((frames, p.size)) for p in net.populations}
    v = {p.id: np.zeros((frames, p.size)) for p in net.populations}
    fired = {p.id: np.zeros((frames, p.size), bool) for p in net.populations}
    for t in range(n_steps):
        for pid in net.population_order():
            pop = pops[pid]
            if pop.source:
                if enc.code.type == "latency":
                    steps = enc.code.spike_steps(vals)
                    raster[pid][t] = (steps == t) & (steps < enc.code.t_max)
                else:
                    raster[pid][t] = enc.code.spikes_at(enc.code.rates(vals), t)
                continue
            p = pop.params
            phase = p.phases[p.phase_index(t + 1)[t]]
            current = np.zeros((frames, pop.size))
            for q in net.incoming(pid):
                for d, m in sorted(mats[q.id].items()):
                    if t >= d:
                        current += raster[q.source][t - d].astype(float) @ m
            u[pid] = (1 - p.du) * u[pid] + current if phase.input_on else 0 * u[pid]
            v[pid] = (1 - p.dv) * v[pid] + (u[pid] + phase.bias)
            s = (v[pid] >= p.v_th) & phase.spiking_on
            if p.reset == "fire_once":
                s &= ~fired[pid]
            elif p.reset == "value":
                v[pid][s] = p.v_reset
            else:
                v[pid][s] -= p.v_th
            fired[pid] |= s
            raster[pid][t] = s
    first = {pid: np.where(r.any(0), r.argmax(0), -1) for pid, r in raster.items()}
    return first, v


def random_recurrent_network(seed: int) -> tuple[SpikingNetwork, np.ndarray]:
    rng = np.random.default_rng(seed)
    n_steps = int(rng.integers(3, 20))
    pops = [Population(id="p0", shape={"r": 2, "i0": int(rng.integers(1, 4))}, source=True)]
    projs = []
    for layer in (1, 2):
        dims = {"r": 2, f"i{layer}": int(rng.integers(1, 4))}
        if rng.random() < 0.5:
            dims = dict(reversed(dims.items()))
        starts = sorted({0, int(rng.integers(1, n_steps + 1))})
        phases = tuple(Phase(start_step=s, bias=float(rng.integers(-2, 5)) / 8,
                             input_on=bool(rng.random() < 0.8),
                             spiking_on=bool(rng.random() < 0.8)) for s in starts)
        params = NeuronParams(du=float(rng.choice([0.0, 0.5, 1.0])),
                              dv=float(rng.choice([0.0, 0.5])),
                              v_th=float(rng.integers(1, 12)) / 4,
                              reset=str(rng.choice(["value", "subtract", "fire_once"])),
                              v_reset=float(rng.integers(-4, 2)) / 4, phases=phases)
        pop = Population(id=f"p{layer}", shape=dims, params=params)
        prev = pops[-1]
        w = rng.integers(-4, 9, size=(prev.shape[f"i{layer - 1}"], dims[f"i{layer}"])) / 4
        projs.append(MatrixProjection(id=f"f{layer}", source=prev.id, target=pop.id,
                                      contract=(f"i{layer - 1}",), produce=(f"i{layer}",),
                                      weights=w, delays=rng.integers(0, 3, size=w.shape)))
        pops.append(pop)
    n1 = pops[1].shape["i1"]
    kernel = rng.integers(-4, 5, size=1 if n1 < 3 else 3) / 4
    kernel[rng.integers(kernel.size)] = 0.5  # non-zero: see the note in the report on _min_delay
    projs.append(StencilProjection(  # recurrent lateral stencil on p1, delays >= 1
        id="lat", source="p1", target="p1", axes=("i1",),
        edge=(str(rng.choice(["wrap", "clip"])),), kernel=kernel,
        delays=rng.integers(1, 3, size=kernel.size)))
    w = rng.integers(-4, 5, size=(pops[2].shape["i2"], n1)) / 4  # feedback p2 → p1
    w[0, 0] = 0.75
    projs.append(MatrixProjection(id="back", source="p2", target="p1", contract=("i2",),
                                  produce=("i1",), weights=w,
                                  delays=rng.integers(1, 4, size=w.shape)))
    code = (LatencyCode(t_max=int(rng.integers(1, n_steps + 1)), x_min=0.0, x_max=1.0)
            if rng.random() < 0.6 else RateCode(max_rate=0.5, phase=0.25))
    net = SpikingNetwork(name="rec", n_steps=n_steps, populations=pops, projections=projs,
                         encoders=[Encoder(port="x", population="p0", code=code)],
                         decoders=[Decoder(port=f"v{i}", population=f"p{i}", kind="membrane")
                                   for i in (1, 2)])
    return net, rng.random((2, *pops[0].dims))


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_step_engine_matches_naive_simulator(seed: int) -> None:
    net, x = random_recurrent_network(seed)
    assert closed_form_problems(net)  # recurrent: only the step engine applies
    r = simulate(net, {"x": x}, mode="auto")
    assert r.mode == "step"
    first, v = naive_simulate(net, x)
    for pid, f in first.items():
        np.testing.assert_array_equal(r.first_spike_steps[pid].reshape(f.shape), f, err_msg=pid)
    for i in (1, 2):
        np.testing.assert_array_equal(r.outputs[f"v{i}"].reshape(v[f"p{i}"].shape), v[f"p{i}"])
