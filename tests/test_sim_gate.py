"""The closed form's gated path (backends/reference/gate.py) equals the step engine exactly.

Random OS-CFAR-like networks: a latency-coded source map (1-D or 2-D, axis order
shuffled per population), fire-once IF targets (``du = 1, dv = 0``, no bias)
fed by one excitatory one-to-one matrix (dense or sparse, some zero weights,
any delay; sometimes split over two projections, as a chip with narrow weights stores
it) and by inhibitory stencils (non-positive dyadic kernels, per-tap
delays, clip or wrap per axis).  The driven path is disabled while the closed
form runs, so each example proves the gated solution itself.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import backends.reference.closed as closed
from backends.reference import build_plan, simulate
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    SpikingNetwork,
    StencilProjection,
)


def _gated_network(seed: int, integer: bool) -> tuple[SpikingNetwork, dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    names = ("range", "doppler")[: int(rng.integers(1, 3))]
    dims = {a: int(rng.integers(1, 7)) for a in names}
    n_steps = int(rng.integers(2, 14))
    order = list(names)
    rng.shuffle(order)
    src = Population(id="in", shape=dims, source=True)
    phases = (Phase(start_step=0),)
    if rng.random() < 0.3:  # a later input cut: the gated segment ends early
        phases += (Phase(start_step=int(rng.integers(1, n_steps + 1)), input_on=False),)
    det = Population(id="det", shape={a: dims[a] for a in order}, params=NeuronParams(
        du=1.0, dv=0.0, v_th=float(rng.integers(1, 9)) / (1 if integer else 4),
        reset="fire_once", phases=phases))
    scale = 1.0 if integer else 0.25
    projs = []
    for i in range(int(rng.integers(0, 3))):
        edge = tuple(str(rng.choice(["clip", "wrap"])) for _ in names)
        kshape = tuple(int(2 * rng.integers(0, 3 if e == "clip" else (dims[a] + 1) // 2) + 1)
                       for a, e in zip(names, edge, strict=True))
        kernel = -scale * rng.integers(0, 4, size=kshape).astype(np.float64)
        projs.append(StencilProjection(
            id=f"train{i}", source="in", target="det", axes=names, kernel=kernel, edge=edge,
            delays=rng.integers(0, 4, size=kshape) if rng.random() < 0.6 else None))
    n = int(np.prod(list(dims.values())))
    w = scale * rng.integers(0, 12, size=n).astype(np.float64)
    delay = int(rng.integers(0, 4))
    sparse, perm = rng.random() < 0.5, rng.permutation(n)  # any one-to-one map
    parts = [w] if rng.random() < 0.6 else [w, scale * rng.integers(0, 5, size=n) * 1.0]
    for i, wp in enumerate(parts):  # a split gate: its parts share the synapses' layout
        if sparse:
            gate = MatrixProjection(id=f"cut{i or ''}", source="in", target="det",
                                    contract=names, produce=names, rows=np.arange(n),
                                    cols=np.arange(n), values=wp, n_in_out=(n, n),
                                    delays=np.full(n, delay, np.int64))
        else:
            dense = np.zeros((n, n))
            dense[perm, np.arange(n)] = wp
            gate = MatrixProjection(id=f"cut{i or ''}", source="in", target="det",
                                    contract=names, produce=names, weights=dense,
                                    delays=np.full((n, n), delay, np.int64))
        projs.insert(int(rng.integers(0, len(projs) + 1)), gate)
    code = LatencyCode(kind=str(rng.choice(["linear", "log"])), t_max=n_steps,
                       x_min=0.1, x_max=1.0)
    net = SpikingNetwork(
        name="gated", n_steps=n_steps, populations=[src, det], projections=projs,
        encoders=[Encoder(port="x", population="in", code=code)],
        decoders=[Decoder(port="det", population="det", kind="spiked"),
                  Decoder(port="v", population="det", kind="membrane")])
    frames = int(rng.integers(1, 3))
    x = rng.uniform(0.1, 1.0, size=(frames, *dims.values()))
    x[rng.random(x.shape) < 0.2] = 0.1  # ties on the grid
    return net, {"x": x}


def _no_driven(*_args, **_kw):
    raise AssertionError("the driven path ran: the gated path did not apply")


def _check(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    integer = seed % 2 == 1
    net, inputs = _gated_network(seed, integer)
    arithmetic = "int64" if integer else "float64"
    assert "det" in build_plan(net, arithmetic=arithmetic).gates
    step = simulate(net, inputs, mode="step", arithmetic=arithmetic, record_spikes=True,
                    out_of_range="clip")
    with monkeypatch.context() as m:
        m.setattr(closed, "driven", _no_driven)
        fast = simulate(net, inputs, mode="closed", arithmetic=arithmetic, record_spikes=True,
                        out_of_range="clip")
    for port in step.outputs:
        np.testing.assert_array_equal(step.outputs[port], fast.outputs[port], err_msg=port)
    np.testing.assert_array_equal(step.first_spike_steps["det"], fast.first_spike_steps["det"])
    assert step.spike_counts == fast.spike_counts
    assert step.synaptic_events == fast.synaptic_events


@settings(max_examples=500, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_gated_closed_form_equals_step(seed: int) -> None:
    with pytest.MonkeyPatch.context() as mp:
        _check(seed, mp)


@pytest.mark.parametrize("seed", range(20))
def test_gated_closed_form_fixed_seeds(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    _check(seed, monkeypatch)


def test_hand_worked_os_decision() -> None:
    """Five cells, training = both neighbours (weight -1), CUT weight 1.5, v_th = 1.

    Linear code on [0, 1] over 10 steps: t = round(10 (1 - x)).  x = [0.9, 0.5, 0.8,
    0.2, 0.7] -> t = [1, 5, 2, 8, 3].  Cell 0 (t=1): its only neighbour (cell 1, t=5)
    comes later, v = 1.5 >= 1 -> fires at 1.  Cell 1 (t=5): both neighbours earlier,
    v = 1.5 - 2 < 1 -> silent.  Cell 2 (t=2): neighbours at 5 and 8 later -> fires at 2.
    Cell 3 (t=8): neighbours at 2 and 3 earlier -> silent.  Cell 4 (t=3): neighbour 3
    at 8 later -> fires at 3.
    """
    net = SpikingNetwork(
        name="os", n_steps=10,
        populations=[Population(id="in", shape={"r": 5}, source=True),
                     Population(id="det", shape={"r": 5}, params=NeuronParams(
                         du=1.0, dv=0.0, v_th=1.0, reset="fire_once"))],
        projections=[StencilProjection(id="train", source="in", target="det", axes=("r",),
                                       kernel=np.array([-1.0, 0.0, -1.0]), edge=("clip",)),
                     MatrixProjection(id="cut", source="in", target="det", contract=("r",),
                                      produce=("r",), weights=1.5 * np.eye(5))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))])
    x = np.array([0.9, 0.5, 0.8, 0.2, 0.7])
    for mode in ("step", "closed"):
        res = simulate(net, {"x": x}, mode=mode)
        assert res.first_spike_steps["det"].ravel().tolist() == [1, -1, 2, -1, 3], mode


def _os_net(cut_weights: np.ndarray, kernel: np.ndarray) -> SpikingNetwork:
    return SpikingNetwork(
        name="os", n_steps=10,
        populations=[Population(id="in", shape={"r": 5}, source=True),
                     Population(id="det", shape={"r": 5}, params=NeuronParams(
                         du=1.0, dv=0.0, v_th=1.0, reset="fire_once"))],
        projections=[StencilProjection(id="train", source="in", target="det", axes=("r",),
                                       kernel=kernel, edge=("clip",)),
                     MatrixProjection(id="cut", source="in", target="det", contract=("r",),
                                      produce=("r",), weights=cut_weights)],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))])


@pytest.mark.parametrize("cut, kernel", [
    (np.eye(5) + np.roll(np.eye(5), 1, axis=0), [-1.0, 0.0, -1.0]),  # two excitatory inputs
    (1.5 * np.eye(5), [-1.0, 0.0, 0.5]),  # an excitatory stencil tap
    (-1.5 * np.eye(5), [-1.0, 0.0, -1.0]),  # no excitatory synapse at all
])
def test_not_gated_falls_back_to_the_driven_path(cut, kernel) -> None:
    net = _os_net(cut, np.array(kernel))
    assert "det" not in build_plan(net).gates
    x = {"x": np.array([0.9, 0.5, 0.8, 0.2, 0.7])}
    np.testing.assert_array_equal(simulate(net, x, mode="step").first_spike_steps["det"],
                                  simulate(net, x, mode="closed").first_spike_steps["det"])


def test_a_split_gate_reaching_a_target_from_two_sources_is_not_gated() -> None:
    x = {"x": np.array([0.9, 0.5, 0.8, 0.2, 0.7])}
    for second, gated in ((np.roll(np.eye(5), 1, axis=0), False), (0.5 * np.eye(5), True)):
        net = _os_net(np.eye(5), np.array([-1.0, 0.0, -1.0]))
        net = SpikingNetwork(name="os", n_steps=net.n_steps, populations=net.populations,
                             encoders=net.encoders, projections=[*net.projections,
                             MatrixProjection(id="cut1", source="in", target="det",
                                              contract=("r",), produce=("r",),
                                              weights=second)])
        gates = build_plan(net).gates
        assert ("det" in gates) == gated and (not gated or gates["det"].split == ("cut1",))
        np.testing.assert_array_equal(simulate(net, x, mode="step").first_spike_steps["det"],
                                      simulate(net, x, mode="closed").first_spike_steps["det"])


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_frames=st.integers(1, 3))
def test_one_source_current_equals_the_sparse_product(seed: int, n_frames: int) -> None:
    """The gate's direct scatter: the bits of ``MatrixDelivery.current`` (±0 included)."""
    from backends.reference.gate import _one_source_currents
    from backends.reference.matrix import MatrixDelivery

    rng = np.random.default_rng(seed)
    n_in, n_out = int(rng.integers(1, 6)), int(rng.integers(1, 7))
    w = np.zeros((n_in, n_out))
    owner = rng.integers(-1, n_in, size=n_out)  # each target: one source or none
    w[owner[owner >= 0], np.flatnonzero(owner >= 0)] = rng.normal(size=int((owner >= 0).sum()))
    proj = MatrixProjection(id="c", source="a", target="b", contract=("i",), produce=("o",),
                            weights=w, delays=np.full(w.shape, 2))
    src = Population(id="a", shape={"r": 2, "i": n_in}, source=True)
    dl = MatrixDelivery.build(proj, src, Population(id="b", shape={"o": n_out, "r": 2}))
    n = n_frames * src.size
    flat = np.sort(rng.choice(n, size=int(rng.integers(0, n + 1)), replace=False))
    values = rng.integers(-2, 5, size=flat.size) * 1.0
    values[values == 0] = rng.choice([0.0, -0.0])
    got = _one_source_currents(dl, flat, [values, np.ones(flat.size)], n_frames)
    assert got is not None
    for x, current in zip([values, np.ones(flat.size)], got, strict=True):
        ref = dl.current(0, flat, n_frames, values=x)
        assert current.shape == ref.shape
        assert np.ascontiguousarray(current).tobytes() == np.ascontiguousarray(ref).tobytes()
    if n_in > 1 and n_out:  # a target with two sources: not this path
        w2 = w.copy()
        w2[:2, 0] = 1.0
        proj2 = MatrixProjection(id="c", source="a", target="b", contract=("i",),
                                 produce=("o",), weights=w2, delays=np.full(w.shape, 2))
        dl2 = MatrixDelivery.build(proj2, src, Population(id="b", shape={"o": n_out, "r": 2}))
        assert _one_source_currents(dl2, flat, [values], n_frames) is None
