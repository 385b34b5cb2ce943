"""Spike delivery: matrix projections along named axes, stencils, delays, shared weights."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference import MatrixDelivery, StencilDelivery, build_plan, simulate
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)

RNG = np.random.default_rng(7)


def _events(spikes: np.ndarray) -> np.ndarray:
    return np.flatnonzero(spikes)


def test_matrix_repetition_axes_transposed() -> None:
    # source (r, c, i), target (o, c, r): reps r and c matched by name, in another order
    src = Population(id="a", shape={"r": 3, "c": 2, "i": 4}, source=True)
    tgt = Population(id="b", shape={"o": 5, "c": 2, "r": 3})
    w = RNG.integers(-4, 5, size=(4, 5)).astype(float)
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=w)
    s = RNG.random((2, 3, 2, 4)) < 0.4
    got = MatrixDelivery.build(proj, src, tgt).current(0, _events(s), 2)
    np.testing.assert_array_equal(got, np.einsum("frci,io->focr", s, w))


def test_matrix_two_contract_axes_flatten_in_contract_order() -> None:
    # contract ("i", "c") → row index i·2 + c, whatever the source's memory order
    src = Population(id="a", shape={"r": 3, "c": 2, "i": 4}, source=True)
    tgt = Population(id="b", shape={"r": 3, "o": 5})
    w = RNG.integers(-4, 5, size=(8, 5)).astype(float)
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i", "c"),
                            produce=("o",), weights=w)
    s = RNG.random((2, 3, 2, 4)) < 0.5
    got = MatrixDelivery.build(proj, src, tgt).current(0, _events(s), 2)
    np.testing.assert_array_equal(got, np.einsum("frci,ico->fro", s, w.reshape(4, 2, 5)))


def test_matrix_two_produce_axes() -> None:
    src = Population(id="a", shape={"i": 3, "r": 2}, source=True)
    tgt = Population(id="b", shape={"p": 2, "r": 2, "o": 4})
    w = RNG.integers(-4, 5, size=(3, 8)).astype(float)  # column o·2 + p (produce order)
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",),
                            produce=("o", "p"), weights=w)
    s = RNG.random((1, 3, 2)) < 0.6
    got = MatrixDelivery.build(proj, src, tgt).current(0, _events(s), 1)
    np.testing.assert_array_equal(got, np.einsum("fir,iop->fpro", s, w.reshape(3, 4, 2)))


def test_sparse_and_dense_weights_give_identical_currents_and_outputs() -> None:
    w = RNG.integers(-3, 4, size=(6, 4)).astype(float) / 4
    w[RNG.random(w.shape) < 0.5] = 0.0
    r, c = np.nonzero(w)
    src = Population(id="a", shape={"r": 2, "i": 6}, source=True)
    tgt = Population(id="b", shape={"o": 4, "r": 2},
                     params=NeuronParams(du=1.0, v_th=0.5, reset="subtract"))
    common = dict(id="w", source="a", target="b", contract=("i",), produce=("o",))
    dense = MatrixProjection(weights=w, **common)
    sparse = MatrixProjection(rows=r, cols=c, values=w[r, c], n_in_out=(6, 4), **common)
    s = RNG.random((3, 2, 6)) < 0.5
    cur = [MatrixDelivery.build(p, src, tgt).current(0, _events(s), 3) for p in (dense, sparse)]
    np.testing.assert_array_equal(cur[0], cur[1])
    x = RNG.random((4, 2, 6))
    outs = []
    for proj in (dense, sparse):
        net = SpikingNetwork(
            name="n", n_steps=12, populations=[src, tgt], projections=[proj],
            encoders=[Encoder(port="x", population="a",
                              code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))],
            decoders=[Decoder(port="n", population="b", kind="count"),
                      Decoder(port="v", population="b", kind="membrane")])
        outs.append(simulate(net, {"x": x}))
    assert outs[0].spike_counts["b"] > 0
    for port in ("n", "v"):
        np.testing.assert_array_equal(outs[0].outputs[port], outs[1].outputs[port])
    assert outs[0].synaptic_events == outs[1].synaptic_events


def brute_stencil(s: np.ndarray, src: Population, tgt: Population,
                  proj: StencilProjection) -> np.ndarray:
    """``I[y] = Σ_o K[o] s[y + o]`` by explicit loops, axes matched by name."""
    out = np.zeros((s.shape[0], *tgt.dims))
    radius = proj.radius
    for f in range(s.shape[0]):
        for y in itertools.product(*(range(n) for n in tgt.dims)):
            pos = dict(zip(tgt.axes, y, strict=True))
            total = 0.0
            for k in itertools.product(*(range(n) for n in proj.kernel.shape)):
                x = dict(pos)
                inside = True
                for axis, ki, rad, edge in zip(proj.axes, k, radius, proj.edge, strict=True):
                    xi = pos[axis] + ki - rad
                    if edge == "wrap":
                        xi %= src.shape[axis]
                    elif not 0 <= xi < src.shape[axis]:
                        inside = False
                    x[axis] = xi
                if inside:
                    total += proj.kernel[k] * s[(f, *(x[a] for a in src.axes))]
            out[(f, *y)] = total
    return out


@pytest.mark.parametrize("edges", [("wrap", "clip"), ("clip", "wrap"), ("clip", "clip"),
                                   ("wrap", "wrap")])
def test_stencil_matches_brute_force(edges: tuple[str, str]) -> None:
    src = Population(id="a", shape={"x": 5, "y": 4, "z": 3}, source=True)
    tgt = Population(id="b", shape={"z": 3, "x": 5, "y": 4})  # same axes, other memory order
    kernel = RNG.integers(-3, 4, size=(3, 5)).astype(float)  # along (y, x)
    proj = StencilProjection(id="k", source="a", target="b", axes=("y", "x"), kernel=kernel,
                             edge=edges)
    s = RNG.random((2, 5, 4, 3)) < 0.3
    d = StencilDelivery.build(proj, src, tgt)
    np.testing.assert_array_equal(d.current(0, _events(s), 2), brute_stencil(s, src, tgt, proj))
    # synaptic events = taps that land inside the map, per spike
    ones = StencilProjection(id="k", source="a", target="b", axes=("y", "x"),
                             kernel=(kernel != 0).astype(float), edge=edges)
    assert d.n_events(0, _events(s)) == brute_stencil(s, src, tgt, ones).sum()


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_stencil_random_shapes_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dims = {a: int(rng.integers(1, 6)) for a in ("x", "y")}
    axes = tuple(a for a in dims if rng.random() < 0.7) or ("x",)
    edge = tuple(str(rng.choice(["wrap", "clip"])) for _ in axes)
    sizes = tuple(int(rng.choice([n for n in (1, 3, 5) if e == "clip" or n <= dims[a]]))
                  for a, e in zip(axes, edge, strict=True))
    kernel = rng.integers(-3, 4, size=sizes).astype(float)
    src = Population(id="a", shape=dims, source=True)
    tgt = Population(id="b", shape=dict(reversed(dims.items())))
    proj = StencilProjection(id="k", source="a", target="b", axes=axes, kernel=kernel, edge=edge)
    s = rng.random((2, *src.dims)) < 0.4
    got = StencilDelivery.build(proj, src, tgt).current(0, _events(s), 2)
    np.testing.assert_array_equal(got, brute_stencil(s, src, tgt, proj))


def _delay_net(delays: np.ndarray) -> SpikingNetwork:
    return SpikingNetwork(
        name="delays", n_steps=8,
        populations=[Population(id="a", shape={"i": 1}, source=True),
                     Population(id="b", shape={"o": 3},
                                params=NeuronParams(du=1.0, v_th=1.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                      produce=("o",), weights=np.ones((1, 3)), delays=delays)],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="b", kind="spike_time", scale=-1.0)])


@pytest.mark.parametrize("mode", ["step", "closed"])
def test_per_synapse_delay(mode: str) -> None:
    # x = 7/8 spikes at step rint((1 - 7/8)·8) = 1; delays 0, 2, 9 → arrivals 1, 3, never (≥ 8)
    net = _delay_net(np.array([[0, 2, 9]]))
    r = simulate(net, {"x": np.array([7 / 8])}, mode=mode)
    assert r.first_spike_steps["b"].tolist() == [[1, 3, -1]]
    assert r.outputs["t"].tolist() == [1.0, 3.0, 0.0]
    assert r.synaptic_events == {"w": 2}  # the delay-9 synapse delivers after the frame


@pytest.mark.parametrize("mode", ["step", "closed"])
def test_stencil_tap_delay(mode: str) -> None:
    # one spike at x = 2 (value 1 → step 0); taps o = -1 (delay 0) and o = +1 (delay 3):
    # y = x - o → y = 3 at step 0, y = 1 at step 3
    net = SpikingNetwork(
        name="sd", n_steps=6,
        populations=[Population(id="a", shape={"x": 5}, source=True),
                     Population(id="b", shape={"x": 5},
                                params=NeuronParams(du=1.0, v_th=1.0, reset="fire_once"))],
        projections=[StencilProjection(id="k", source="a", target="b", axes=("x",),
                                       kernel=np.array([1.0, 0.0, 1.0]), edge=("clip",),
                                       delays=np.array([0, 0, 3]))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=6, x_min=0.0, x_max=1.0))])
    r = simulate(net, {"x": np.array([0.0, 0.0, 1.0, 0.0, 0.0])}, mode=mode)
    assert r.first_spike_steps["b"].tolist() == [[-1, 3, -1, 0, -1]]


def _repeated_net(reps: int, sparse: bool) -> SpikingNetwork:
    w = np.arange(12, dtype=float).reshape(4, 3) - 5
    common = dict(id="w", source="a", target="b", contract=("i",), produce=("o",))
    proj = (MatrixProjection(rows=np.nonzero(w)[0], cols=np.nonzero(w)[1], values=w[w != 0],
                             n_in_out=(4, 3), **common) if sparse
            else MatrixProjection(weights=w, **common))
    return SpikingNetwork(
        name="reps", n_steps=4,
        populations=[Population(id="a", shape={"chirp": reps, "i": 4}, source=True),
                     Population(id="b", shape={"o": 3, "chirp": reps})],
        projections=[proj],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])


@pytest.mark.parametrize("sparse", [False, True])
def test_plan_memory_flat_in_repetitions(sparse: bool) -> None:
    small, big = (build_plan(_repeated_net(n, sparse)) for n in (1, 1000))
    assert small.weight_nbytes == big.weight_nbytes
    assert big.deliveries["w"].n_reps == 1000
    (w,) = big.deliveries["w"].weights
    assert w.shape == (4, 3)
    if not sparse:  # dense without delays: the projection's own array, not a copy
        assert w is big.network.projection["w"].weights


def test_matrix_projection_with_no_contracted_axis_broadcasts_each_neuron():
    """``contract=()``: every source neuron is one row (n_in = 1) feeding the produced axes."""
    import numpy as np

    from backends.reference import simulate
    from compiler.snn import (
        Decoder,
        Encoder,
        LatencyCode,
        MatrixProjection,
        NeuronParams,
        Population,
        SpikingNetwork,
    )

    net = SpikingNetwork(
        name="fanout", n_steps=4,
        populations=[Population(id="a", shape={"r": 3}, source=True),
                     Population(id="b", shape={"r": 3, "o": 2},
                                params=NeuronParams(v_th=1.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=(),
                                      produce=("o",), weights=np.array([[1.0, 0.5]]))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="y", population="b", kind="spiked")])
    for mode in ("step", "closed"):
        out = simulate(net, {"x": np.array([1.0, 0.0, 1.0])}, mode=mode).outputs["y"]
        assert out.tolist() == [[1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]
