"""The resonators' closed form (backends/reference/resonator_closed.py): bit-equal to the step
engine and to the step-by-step replay it replaces, in int64 and float64, on random drives —
shared and per-bin weights, renormalised populations, axes around the bins, several frames,
states too large for the exact float replay — and its rounding identity exhaustively."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import backends.reference.closed as closed
import backends.reference.resonator_closed as resonator_closed
from backends.reference import build_plan, simulate
from backends.reference.fired import Fired
from backends.reference.resonator import _shift, solve_resonator
from backends.reference.resonator_closed import _AWAY
from backends.reference.resonator_drive import shared_drive
from backends.reference.spans import Arrivals, charge, drive
from compiler.snn import Decoder, Encoder, MatrixProjection, Population, SpikingNetwork
from compiler.snn.resonator import Phase, ResonatorParams
from compiler.snn.stream import StreamCode


def _old_solve(plan, pid, arrivals, n_frames, first):
    """The closed form before: the step arithmetic over the full drive histogram."""
    pop = plan.populations[pid]
    dtype = np.int64 if plan.integer else np.float64
    return solve_resonator(plan.neurons[pid],
                           lambda s0, s1: drive(arrivals, s0, s1, n_frames, pop.dims, dtype),
                           n_frames * pop.size, first, charge)


def _network(k, q, bits, group, n_in, t_out, coef_bits, seed, renorm=0, per_bin=False,
             frac=False, c_axis=2, delay=0, bit_base=2.0):
    """A stream source ``{c, bit, q, part: 2}`` fanned out to resonators ``{c, k, q, part}``
    through one projection per group of ``group`` bits (``per_bin``: a bin-dependent weight,
    so no shared drive; ``frac``: fractional weights; ``delay``: the odd bits' synapses;
    ``bit_base``: bit ``b`` weighted ``bit_base^b``, not a level's ``2^b`` unless 2)."""
    rng = np.random.default_rng(seed)
    one = 2.0 ** coef_bits if coef_bits else 1.0
    theta = rng.uniform(-np.pi, np.pi, k)
    rho = rng.choice([1.0, 0.95])
    c, s = rho * one * np.cos(theta), rho * one * np.sin(theta)
    if coef_bits:
        c, s = np.trunc(c), np.trunc(s)
    ends = {}
    if renorm:
        te = rng.uniform(-np.pi, np.pi, k)
        ends = {"renorm_steps": renorm, "cos_end": tuple(np.trunc(rho * one * np.cos(te))),
                "sin_end": tuple(np.trunc(rho * one * np.sin(te)))}
    phases = (Phase(start_step=0, spiking_on=False),
              Phase(start_step=n_in, bias=2.0, input_on=False),
              Phase(start_step=n_in + t_out, input_on=False, spiking_on=False))
    params = ResonatorParams(axis="k", cos=tuple(c), sin=tuple(s), coef_bits=coef_bits,
                             v_th=2.0 * t_out + 1, phases=phases, **ends)
    projections = []
    for g, lo in enumerate(range(0, bits, group)):
        b, p, kk = (a.ravel() for a in np.meshgrid(np.arange(lo, min(bits, lo + group)),
                                                   np.arange(2), np.arange(k), indexing="ij"))
        values = bit_base ** b * (1 + kk if per_bin else 1) * (0.75 if frac else 1)
        projections.append(MatrixProjection(
            id=f"w{g}", source="in", target="out", contract=("bit", "part"),
            produce=("k", "part"), rows=b * 2 + p, cols=kk * 4 + p, values=values,
            n_in_out=(2 * bits, 4 * k), delays=(b % 2) * delay if delay else None))
    code = StreamCode(axis="n", length=n_in, inner=2 * q, bits=bits, x_max=1.0)
    return SpikingNetwork(
        name="res", n_steps=n_in + t_out + 1,
        populations=[Population(id="in", shape={"c": c_axis, "bit": bits, "q": q, "part": 2},
                                source=True),
                     Population(id="out", shape={"c": c_axis, "k": k, "q": q, "part": 4},
                                params=params)],
        projections=projections,
        encoders=[Encoder(port="x", population="in", split="signed", code=code)],
        decoders=[Decoder(port="v", population="out", kind="membrane", combine="re_im_signed")])


def _runs(net, x, arith):
    step = simulate(net, {"x": x}, mode="step", arithmetic=arith)
    new = simulate(net, {"x": x}, mode="closed", arithmetic=arith)
    with mock.patch.object(closed, "solve_resonators", _old_solve):
        old = simulate(net, {"x": x}, mode="closed", arithmetic=arith)
    return step, new, old


def _assert_equal(a, b):
    for pid in ("in", "out"):  # the stream source's raster bookkeeping too
        np.testing.assert_array_equal(a.first_spike_steps[pid], b.first_spike_steps[pid])
    assert a.spike_counts == b.spike_counts
    np.testing.assert_array_equal(a.outputs["v"], b.outputs["v"])
    assert a.synaptic_events == b.synaptic_events


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 6), q=st.integers(1, 3), bits=st.integers(1, 8),
       group=st.integers(1, 8), n_in=st.integers(1, 24), t_out=st.integers(1, 8),
       frames=st.integers(1, 3), seed=st.integers(0, 2 ** 16),
       coef_bits=st.sampled_from([4, 8, 12, 16]), renorm=st.sampled_from([0, 0, 2, 3, 7]),
       per_bin=st.booleans(), arith=st.sampled_from(["int64", "float64"]),
       delay=st.sampled_from([0, 0, 1, 3]))
def test_fixed_point_closed_form_is_the_step_engine(k, q, bits, group, n_in, t_out, frames,
                                                    seed, coef_bits, renorm, per_bin, arith,
                                                    delay):
    net = _network(k, q, bits, group, n_in, t_out, coef_bits, seed, renorm=renorm,
                   per_bin=per_bin, delay=delay)
    x = np.random.default_rng(seed + 1).uniform(-1, 1, (frames, 2, n_in, q))
    step, new, old = _runs(net, x, arith)
    _assert_equal(step, new)
    _assert_equal(old, new)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 4), n_in=st.integers(2, 16), seed=st.integers(0, 2 ** 16),
       renorm=st.sampled_from([0, 3]), arith=st.sampled_from(["int64", "float64"]))
def test_states_beyond_the_exact_float_replay_take_the_step_arithmetic(k, n_in, seed, renorm,
                                                                       arith):
    # 30 fraction bits and 24-bit levels: |u| may pass 2^(49 − 30), so the replay falls back
    # (and the drive's weights sum past 2^24: its product runs in float64)
    net = _network(k, 1, 24, 24, n_in, 2, 30, seed, renorm=renorm)
    x = np.random.default_rng(seed).uniform(-1, 1, (2, 2, n_in, 1))
    with mock.patch.object(resonator_closed, "_replay_steps",
                           wraps=resonator_closed._replay_steps) as fallback:
        step, new, old = _runs(net, x, arith)
    assert fallback.called
    _assert_equal(step, new)
    _assert_equal(old, new)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 4), n_in=st.integers(1, 12), seed=st.integers(0, 2 ** 16))
def test_fractional_weights_in_float64_keep_the_step_sums(k, n_in, seed):
    net = _network(k, 2, 4, 2, n_in, 3, 12, seed, frac=True)
    x = np.random.default_rng(seed).uniform(-1, 1, (2, 2, n_in, 2))
    step, new, old = _runs(net, x, "float64")
    _assert_equal(step, new)
    _assert_equal(old, new)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 6), q=st.integers(1, 3), n_in=st.integers(1, 20),
       seed=st.integers(0, 2 ** 16), per_bin=st.booleans())
def test_float_closed_form_agrees_with_the_step_engine_to_rounding(k, q, n_in, seed, per_bin):
    net = _network(k, q, 6, 3, n_in, 4, 0, seed, per_bin=per_bin)
    x = np.random.default_rng(seed).uniform(-1, 1, (2, 2, n_in, q))
    step, new, old = _runs(net, x, "float64")
    np.testing.assert_allclose(new.outputs["v"], step.outputs["v"], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(new.outputs["v"], old.outputs["v"], rtol=1e-9, atol=1e-9)


def test_shared_drive_only_where_every_bin_has_the_same_weights():
    for per_bin, shared in ((False, True), (True, False)):
        net = _network(3, 2, 4, 2, 5, 2, 12, 0, per_bin=per_bin)
        plan = build_plan(net, "int64")
        none = Fired.of_events(np.zeros(0, np.int64), np.zeros(0, np.int64), net.n_steps)
        arrivals = [Arrivals(plan.deliveries[q], 0, 0, none, net.n_steps)
                    for q in plan.incoming["out"]]
        got = shared_drive(plan, "out", arrivals, 1, 0, 5)
        assert (got is not None) == shared
        if shared:
            assert got.shape == (5, 1, 2, 1, 2) and not got.any()


@pytest.mark.parametrize("bits", [1, 2, 5, 12])
def test_rint_of_the_nudged_product_rounds_half_away_from_zero(bits):
    # every multiple of 2^-F in a window, and far out where the float replay still applies
    q = np.concatenate([np.arange(-(8 << bits), 8 << bits),
                        np.random.default_rng(bits).integers(-(2 ** 48), 2 ** 48, 10000)])
    q = q[np.abs(q) < 2.0 ** 49]
    u = q * 2.0 ** -bits
    np.testing.assert_array_equal(np.rint(u * _AWAY), _shift(q, bits, True))
    np.testing.assert_array_equal(np.rint(u * _AWAY), _shift(q.astype(float), bits, False))


@settings(max_examples=60, deadline=None)
@given(length=st.integers(1, 9), inner=st.integers(1, 6), bits=st.integers(1, 16),
       pre=st.integers(1, 4), frames=st.integers(1, 3), seed=st.integers(0, 2 ** 16),
       gains=st.booleans())
def test_bit_planes_are_the_bits_of_the_levels(length, inner, bits, pre, frames, seed, gains):
    rng = np.random.default_rng(seed)
    code = StreamCode(axis="n", length=length, inner=inner, bits=bits, x_max=1.0,
                      gains=tuple(rng.uniform(0, 1.2, length)) if gains else ())
    x = rng.uniform(0, 1.1, (frames, pre * length * inner))
    g = np.asarray(code.gains) if gains else np.ones(length)
    z = x.reshape(frames, pre, length, inner) * g[None, None, :, None]
    q = code.levels(z)
    want = np.zeros((length, frames, pre, bits, inner), bool)
    for b in range(bits):  # plane n, neuron (frame, pre, bit, inner): bit b of the level
        want[:, :, :, b, :] = np.moveaxis((q >> b) & 1, 2, 0) == 1
    np.testing.assert_array_equal(code.bit_planes(x), want.reshape(length, -1))


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 40), n_steps=st.integers(1, 12), seed=st.integers(0, 2 ** 16))
def test_first_spike_steps_of_repeated_events_are_the_earliest(n, n_steps, seed):
    from backends.reference.order import first_spike_steps

    rng = np.random.default_rng(seed)
    raster = rng.random((n_steps, n)) < rng.uniform(0.05, 0.9)
    step, flat = np.nonzero(raster)  # ordered by step, then neuron
    want = np.where(raster.any(axis=0), raster.argmax(axis=0), -1)
    np.testing.assert_array_equal(first_spike_steps(flat, step, n), want)


@settings(max_examples=60, deadline=None)
@given(rb=st.integers(1, 12), k=st.integers(1, 9), p=st.integers(1, 4), m=st.integers(1, 3),
       shared=st.booleans(), seed=st.integers(0, 2 ** 16))
def test_drive_added_by_rank_one_updates_is_the_plain_sum(rb, k, p, m, shared, seed):
    from backends.reference.resonator_closed import _drive_adder

    rng = np.random.default_rng(seed)

    def whole(*shape):
        return rng.integers(-2 ** 40, 2 ** 40, shape) + 1j * rng.integers(-2 ** 40, 2 ** 40,
                                                                          shape)

    block = whole(rb, k, p)
    d = whole(m, rb + 3, 1 if shared else k, p)[:, 1:1 + rb]  # a row slice, as in the replay
    want = block.copy()
    add = _drive_adder(block, d)
    for j in range(m):  # the adder writes into block itself, step after step
        want += d[j]
        add(j)
        np.testing.assert_array_equal(block, want)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 4), q=st.integers(1, 3), bits=st.integers(2, 6), n_in=st.integers(1, 12),
       frames=st.integers(1, 3), seed=st.integers(0, 2 ** 16), delay=st.sampled_from([0, 2]),
       arith=st.sampled_from(["int64", "float64"]))
def test_bit_weights_that_are_not_the_levels_take_the_raster(k, q, bits, n_in, frames, seed,
                                                             delay, arith):
    # weights 3^b: the drive is not (levels & mask)·V, so the shared drive multiplies the
    # bit planes, still the step engine's sums
    from backends.reference import resonator_drive

    net = _network(k, q, bits, 3, n_in, 2, 12, seed, bit_base=3.0, delay=delay)
    x = np.random.default_rng(seed).uniform(-1, 1, (frames, 2, n_in, q))
    with mock.patch.object(resonator_drive, "_add_raster_drive",
                           wraps=resonator_drive._add_raster_drive) as raster:
        step, new, old = _runs(net, x, arith)
    assert raster.called  # (a delay class holding bit 0 alone still factors)
    _assert_equal(step, new)
    _assert_equal(old, new)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 4), q=st.integers(1, 3), bits=st.integers(1, 10), group=st.integers(1, 10),
       n_in=st.integers(1, 12), frames=st.integers(1, 3), seed=st.integers(0, 2 ** 16),
       delay=st.sampled_from([0, 1, 3]), arith=st.sampled_from(["int64", "float64"]))
def test_level_drive_is_the_step_engine(k, q, bits, group, n_in, frames, seed, delay, arith):
    # levels split over projections by bit groups (masks), delayed odd bits
    from backends.reference import resonator_drive

    net = _network(k, q, bits, group, n_in, 2, 12, seed, delay=delay)
    x = np.random.default_rng(seed).uniform(-1, 1, (frames, 2, n_in, q))
    with mock.patch.object(resonator_drive, "_add_raster_drive",
                           wraps=resonator_drive._add_raster_drive) as raster:
        step, new, old = _runs(net, x, arith)
    assert not raster.called
    _assert_equal(step, new)
    _assert_equal(old, new)


@settings(max_examples=60, deadline=None)
@given(m=st.integers(1, 5), r=st.integers(0, 4), seed=st.integers(0, 2 ** 16))
def test_largest_component_bounds_the_modulus(m, r, seed):
    from backends.reference.resonator_closed import _SQRT2, _largest

    rng = np.random.default_rng(seed)
    d = rng.normal(size=(m, r, 2)) @ np.array([1, 1j]) * 10.0 ** rng.integers(0, 12)
    top = _largest(d)
    want = np.abs(d).max(axis=1, initial=0.0)
    assert np.all(want <= _SQRT2 * top) and np.all(top <= want)
    assert _largest(np.zeros((2, 0), complex)).tolist() == [0.0, 0.0]


def test_exact_bound_refuses_a_fractional_drive_unless_told_it_is_whole():
    from backends.reference.resonator_closed import _exact

    z, a = np.zeros((1, 1, 1), complex), np.full((1, 1), 0.5 + 0j)
    half = np.full((1, 1, 1, 1), 0.5 + 0j)
    assert not _exact(z, half, a, None, 12)
    assert _exact(z, np.ones((1, 1, 1, 1), complex), a, None, 12)
    big = np.full((1, 1, 1, 1), 2.0 ** 40 + 0j)  # 2^(F+1)·|z + d| reaches 2^52
    assert not _exact(z, big, a, None, 12, whole=True)


@settings(max_examples=60, deadline=None)
@given(shape=st.lists(st.integers(1, 4), min_size=3, max_size=3), seed=st.integers(0, 2 ** 16),
       integer=st.booleans())
def test_compartments_are_re_minus_re_im_minus_im(shape, seed, integer):
    from backends.reference.resonator_closed import _project
    rng = np.random.default_rng(seed)
    z = np.empty(shape, np.complex128)
    z.real, z.imag = (rng.choice([0.0, -0.0, 1.0, -7.0, 2.0 ** 40], shape) for _ in range(2))
    dt = np.int64 if integer else np.float64
    want = np.empty((*shape, 4), dt)
    want[..., 0], want[..., 2] = z.real, z.imag
    want[..., 1], want[..., 3] = -want[..., 0], -want[..., 2]
    got = _project(z, dt)
    assert got.dtype == dt and got.tobytes() == want.reshape(-1).tobytes()


@settings(max_examples=40, deadline=None)
@given(rows=st.integers(1, 9), k=st.integers(1, 6), p=st.integers(1, 3),
       n_steps=st.integers(1, 12), block=st.integers(1, 64), shared=st.booleans(),
       seed=st.integers(0, 2**32 - 1))
def test_the_replay_block_never_changes_a_bit(rows, k, p, n_steps, block, shared, seed):
    """Any block size — the cache-sized one, the larger one taken while other threads run,
    or a row at a time — gives the same bits (the replay is elementwise along the rows)."""
    import threading

    rng = np.random.default_rng(seed)
    z = (rng.integers(-500, 500, (rows, k, p))
         + 1j * rng.integers(-500, 500, (rows, k, p))).astype(np.complex128)
    a = np.exp(1j * rng.uniform(0, 2 * np.pi, (k, p))) * rng.integers(1000, 4096, (k, p)) / 4096
    a = np.round(a * 4096) / 4096  # a 12-bit coefficient, divided by 2^F
    d = (rng.integers(-50, 50, (n_steps, rows, 1 if shared else k, p))
         + 1j * rng.integers(-50, 50, (n_steps, rows, 1 if shared else k, p)))
    whole = resonator_closed.replay_rows(z, a, n_steps, d.astype(np.complex128),
                                         block_entries=rows * k * p)
    blocked = resonator_closed.replay_rows(z, a, n_steps, d.astype(np.complex128),
                                           block_entries=block)
    assert blocked.tobytes() == whole.tobytes()
    idle = threading.Event()
    other = threading.Thread(target=idle.wait)  # another thread alive: the shared block
    other.start()
    try:
        picked = resonator_closed.replay_rows(z, a, n_steps, d.astype(np.complex128))
    finally:
        idle.set()
        other.join()
    assert picked.tobytes() == whole.tobytes()
