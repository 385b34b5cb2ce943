"""The resonator neuron in the reference simulator: hand traces, the stream code, and the
closed form equal to the step engine on every network of the motif (hypothesis)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from backends.reference import simulate
from backends.reference.encoding import StreamTrain
from backends.reference.resonator import (
    LiveResonators,
    ResonatorState,
    ResonatorStepParams,
    resonator_step,
    rotate,
)
from compiler.snn import Decoder, Encoder, MatrixProjection, Population, SpikingNetwork
from compiler.snn.resonator import Phase, ResonatorParams
from compiler.snn.stream import StreamCode
from ir.errors import NetworkError


def _params(**kw) -> ResonatorParams:
    base = {"axis": "k", "cos": (1.0,), "sin": (0.0,), "v_th": 4.0,
            "phases": (Phase(start_step=0, spiking_on=False),
                       Phase(start_step=2, bias=1.0, input_on=False))}
    return ResonatorParams(**{**base, **kw})


def test_hand_trace_quarter_turns_then_charging():
    # θ = π/2: z = a (z + d); fed 1 then 0; then held, each compartment charges by 1
    p = ResonatorStepParams.of(_params(cos=(0.0,), sin=(1.0,)), 6, shape={"k": 1, "part": 4})
    state, trace = ResonatorState.zeros(1), []
    for t, x in enumerate([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]):
        s, state = resonator_step(state, np.array([x, 0, 0, 0.0]), p, t)
        trace.append((complex(state.x[0], state.y[0]) + 0, state.v.tolist(),
                      np.flatnonzero(s).tolist()))
    assert trace[0][0] == 1j and trace[1][0] == -1 + 0j
    # after step 1: v = (Re, −Re, Im, −Im) = (−1, 1, 0, 0); then +1 per step; v_th = 4
    assert trace[1][1] == [-1.0, 1.0, 0.0, 0.0]
    assert trace[2][1] == [0.0, 2.0, 1.0, 1.0]
    assert [tr[2] for tr in trace] == [[], [], [], [], [1], [2, 3]]  # 1 + 3, 0 + 4 reach 4


def test_fixed_point_rounds_half_away_from_zero():
    x, y = rotate(np.array([3, -3]), np.array([0, 0]), np.array([2048, 2048]),
                  np.array([0, 0]), 12, True)
    assert x.tolist() == [2, -2] and y.tolist() == [0, 0]  # ±1.5 → ±2
    xf, _ = rotate(np.array([3.0, -3.0]), np.zeros(2), np.array([2048.0] * 2), np.zeros(2), 12,
                   False)
    assert xf.tolist() == [2.0, -2.0]


def test_resonator_computes_the_dft_exactly_in_float():
    n = 16
    theta = 2 * np.pi * np.arange(n) / n
    p = ResonatorStepParams.of(_params(cos=tuple(np.cos(theta)), sin=tuple(np.sin(theta)),
                                       phases=(Phase(start_step=0, spiking_on=False),)),
                               n, shape={"k": n, "part": 4})
    x = np.random.default_rng(1).normal(size=n)
    state = ResonatorState.zeros(n)
    for t in range(n):
        cur = np.zeros(4 * n)
        cur[0::4] = x[t]  # +Re compartment of every bin: one fan-out synapse each
        _, state = resonator_step(state, cur, p, t)
    np.testing.assert_allclose(state.x + 1j * state.y, np.fft.fft(x), atol=1e-12)


def test_hand_trace_renormalisation_turns_on_the_block_end_steps():
    # â = 1 (no turn), ĉ = i (a quarter turn) every 2nd step counted back from the last
    # input step 4: steps 0, 2, 4 turn; fed 8 at step 0, the state is 8i, −8, then 8i·i² …
    one = 4096.0
    par = _params(cos=(one,), sin=(0.0,), coef_bits=12, renorm_steps=2, cos_end=(0.0,),
                  sin_end=(one,), phases=(Phase(start_step=0, spiking_on=False),
                                          Phase(start_step=5, input_on=False)))
    p = ResonatorStepParams.of(par, 6, integer=True, shape={"k": 1, "part": 4})
    assert par.renorm_schedule(6).tolist() == [True, False, True, False, True, False]
    state, zs = ResonatorState.zeros(1, integer=True), []
    for t, x in enumerate([8, 0, 0, 0, 0, 0]):
        _, state = resonator_step(state, np.array([x, 0, 0, 0]), p, t)
        zs.append(complex(int(state.x[0]), int(state.y[0])))
    assert zs == [8j, 8j, -8, -8, -8j, -8j]


def test_renormalised_params_refuse_growth_float_and_missing_ends():
    one = 4096.0
    base = {"cos": (one,), "sin": (0.0,), "coef_bits": 12}
    with pytest.raises(ValueError, match="must not grow the state"):
        _params(**base, renorm_steps=2, cos_end=(one,), sin_end=(one,))
    with pytest.raises(ValueError, match="at most 2\\^12"):
        _params(**base, renorm_steps=2, cos_end=(one + 1,), sin_end=(0.0,))
    with pytest.raises(ValueError, match="needs fixed-point"):
        _params(cos=(1.0,), sin=(0.0,), renorm_steps=2, cos_end=(1.0,), sin_end=(0.0,))
    with pytest.raises(ValueError, match="one value per index"):
        _params(**base, renorm_steps=2)
    with pytest.raises(ValueError, match="for renorm_steps > 0"):
        _params(**base, cos_end=(one,), sin_end=(0.0,))
    # a step coefficient just outside the unit circle is allowed when every block shrinks
    _params(cos=(one,), sin=(30.0,), coef_bits=12, renorm_steps=4, cos_end=(4000.0,),
            sin_end=(0.0,))


def test_params_refuse_growth_and_spiking_while_rotating():
    with pytest.raises(ValueError, match="at most 1"):
        _params(cos=(1.0,), sin=(0.1,))
    with pytest.raises(ValueError, match="no phase may have both on"):
        _params(phases=(Phase(start_step=0),))
    with pytest.raises(ValueError, match="whole numbers"):
        _params(cos=(0.5,), coef_bits=4)


def test_network_refuses_a_resonator_without_four_compartments():
    with pytest.raises(NetworkError, match="trailing 'part' axis of 4"):
        SpikingNetwork(name="n", n_steps=4, populations=[
            Population(id="r", shape={"k": 1, "part": 2}, params=_params())]).validate()


def test_stream_train_sends_levels_as_bit_planes():
    code = StreamCode(axis="n", length=3, inner=1, bits=3, x_max=7.0, gains=(1.0, 0.5, 1.0))
    tr = StreamTrain.build(code, np.array([[5.0, 6.0, 7.0]]), n_steps=5)
    # levels 5 = 101b, 6·0.5 = 3 = 011b, 7 = 111b: bit neurons 0, 1, 2
    assert [tr.events_at(t).tolist() for t in range(4)] == [[0, 2], [0, 1], [0, 1, 2], []]


def _network(k, bits, frames_fixed, t_out, theta, rho, coef_bits, scales, renorm=0,
             theta_end=None):
    """A stream source (real input, ± parts) feeding ``k`` resonators, time read-out
    (``renorm`` > 0: block-end coefficients at ``theta_end`` every ``renorm`` steps)."""
    r = rho * (2.0 ** coef_bits if coef_bits else 1.0)
    c, s = r * np.cos(theta), r * np.sin(theta)
    if coef_bits:
        c, s = np.trunc(c), np.trunc(s)
    ends = {}
    if renorm:
        ends = {"renorm_steps": renorm, "cos_end": tuple(np.trunc(r * np.cos(theta_end))),
                "sin_end": tuple(np.trunc(r * np.sin(theta_end)))}
    n_in = frames_fixed
    phases = (Phase(start_step=0, spiking_on=False),
              Phase(start_step=n_in, bias=2.0, input_on=False),
              Phase(start_step=n_in + t_out, input_on=False, spiking_on=False))
    extra = {"scale_axis": "k", "scales": tuple(scales)} if scales else {}
    params = ResonatorParams(axis="k", cos=tuple(c), sin=tuple(s), coef_bits=coef_bits,
                             v_th=2.0 * t_out + 1, phases=phases, **extra, **ends)
    b, p, q = (a.ravel() for a in np.meshgrid(np.arange(bits), np.arange(2), np.arange(k),
                                              indexing="ij"))
    proj = MatrixProjection(id="w", source="in", target="out", contract=("bit", "part"),
                            produce=("k", "part"), rows=b * 2 + p, cols=q * 4 + p,
                            values=2.0 ** b, n_in_out=(2 * bits, 4 * k))
    code = StreamCode(axis="n", length=n_in, inner=2, bits=bits, x_max=1.0)
    return SpikingNetwork(
        name="res", n_steps=n_in + t_out + 1,
        populations=[Population(id="in", shape={"c": 2, "bit": bits, "part": 2}, source=True),
                     Population(id="out", shape={"c": 2, "k": k, "part": 4}, params=params)],
        projections=[proj],
        encoders=[Encoder(port="x", population="in", split="signed", code=code)],
        decoders=[Decoder(port="y", population="out", kind="spike_time", t_ref=n_in + t_out,
                          combine="re_im_signed"),
                  Decoder(port="v", population="out", kind="membrane", combine="re_im_signed")])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(k=st.integers(1, 5), bits=st.integers(1, 5), n_in=st.integers(1, 12),
       t_out=st.integers(1, 16), seed=st.integers(0, 2 ** 16), fixed=st.booleans(),
       rho=st.sampled_from([1.0, 0.9]), scaled=st.booleans(), frames=st.integers(1, 3),
       renorm=st.sampled_from([0, 0, 2, 3, 5]))
def test_closed_form_equals_step_engine(k, bits, n_in, t_out, seed, fixed, rho, scaled,
                                        frames, renorm):
    rng = np.random.default_rng(seed)
    theta = rng.uniform(-np.pi, np.pi, k)
    scales = tuple(float(v) for v in rng.integers(1, 4, k)) if scaled else ()
    net = _network(k, bits, n_in, t_out, theta, rho, 12 if fixed else 0, scales,
                   renorm=renorm if fixed else 0, theta_end=rng.uniform(-np.pi, np.pi, k))
    x = rng.uniform(-1, 1, (frames, 2, n_in))
    arith = "int64" if fixed else "float64"
    a = simulate(net, {"x": x}, mode="step", arithmetic=arith, record_spikes=True)
    b = simulate(net, {"x": x}, mode="closed", arithmetic=arith)
    assert a.synaptic_events == b.synaptic_events
    if fixed:  # the same integer arithmetic: every spike and membrane equal
        np.testing.assert_array_equal(a.first_spike_steps["out"], b.first_spike_steps["out"])
        np.testing.assert_array_equal(a.outputs["v"], b.outputs["v"])
        return
    # floating point: the power sum agrees with the recurrence to rounding; the thresholds
    # are odd and the charges even whole numbers, so no irrational membrane sits on a boundary
    np.testing.assert_allclose(a.outputs["v"], b.outputs["v"], rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(a.first_spike_steps["out"], b.first_spike_steps["out"])


def test_live_population_matches_the_pure_step_function():
    p = ResonatorStepParams.of(_params(cos=(0.6,), sin=(0.8,)), 6, shape={"k": 1, "part": 4})
    live, state = LiveResonators(p, 4), ResonatorState.zeros(1)

    def add(c, out):
        out += c

    for t in range(6):
        cur = np.array([1.0, 0.0, 0.25, 0.0])
        got = live.step(t, [cur], add)
        s, state = resonator_step(state, cur, p, t)
        assert got.tolist() == np.flatnonzero(s).tolist()
    np.testing.assert_array_equal(live.v, state.v)
