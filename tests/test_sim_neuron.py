"""Hand-worked traces of the neuron step function (numbers reasoned out by hand, Norse-style).

Every expected value below was computed on paper from the update of
``compiler.snn.neurons``:  ``u = (1-du)·u + I`` (or 0 with the input off),
``v = (1-dv)·v + (u + b)``, spike if ``v >= v_th`` and spiking is on, then reset.
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import NeuronState, StepParams, decay, neuron_step
from compiler.snn import NeuronParams, Phase


def run_trace(params: NeuronParams, currents: list[float], integer: bool = False):
    """Drive one neuron with ``currents``; return (spikes, u, v) per step."""
    p = StepParams.from_params(params, n_steps=len(currents), integer=integer)
    state = NeuronState.zeros((1,), integer=integer)
    dtype = np.int64 if integer else np.float64
    spikes, us, vs = [], [], []
    for t, i in enumerate(currents):
        s, state = neuron_step(state, np.array([i], dtype), p, t)
        spikes.append(bool(s[0]))
        us.append(state.u[0].item())
        vs.append(state.v[0].item())
    return spikes, us, vs


def test_if_subtract_reset() -> None:
    # v: .375 .75 1.125→spike→.125 .5 .875 1.25→spike→.25 .625 1.0→spike→0
    spikes, us, vs = run_trace(NeuronParams(du=1.0, dv=0.0, v_th=1.0, reset="subtract"),
                               [0.375] * 8)
    assert spikes == [False, False, True, False, False, True, False, True]
    assert vs == [0.375, 0.75, 0.125, 0.5, 0.875, 0.25, 0.625, 0.0]
    assert us == [0.375] * 8


def test_lif_decay_du_and_dv() -> None:
    # u halves each step (du = .5); v keeps 3/4 (dv = .25) and adds u:
    # v0 = 1; v1 = .75 + .5; v2 = .9375 + .25; v3 = .890625 + .125; v4 = .76171875 + 2.0625
    spikes, us, vs = run_trace(NeuronParams(du=0.5, dv=0.25, v_th=10.0), [1.0, 0, 0, 0, 2.0])
    assert us == [1.0, 0.5, 0.25, 0.125, 2.0625]
    assert vs == [1.0, 1.25, 1.1875, 1.015625, 2.82421875]
    assert not any(spikes)


def test_lif_value_reset() -> None:
    # as above with v_th = 1.2, v_reset = -.5: spike at 1 (1.25) → -.5;
    # v2 = -.375 + .25 = -.125; v3 = -.09375 + .125 = .03125; v4 = .0234375 + 2.0625 → spike → -.5
    spikes, _, vs = run_trace(NeuronParams(du=0.5, dv=0.25, v_th=1.2, reset="value",
                                           v_reset=-0.5), [1.0, 0, 0, 0, 2.0])
    assert spikes == [False, True, False, False, True]
    assert vs == [1.0, -0.5, -0.125, 0.03125, -0.5]


def test_ramp_neuron() -> None:
    # du = dv = 0: u integrates the input, v integrates u: V(T) = Σ w (T - t_in)
    spikes, us, vs = run_trace(NeuronParams(du=0.0, dv=0.0, v_th=100.0), [0, 2.0, 0, -1.0, 0])
    assert us == [0.0, 2.0, 2.0, 1.0, 1.0]
    assert vs == [0.0, 2.0, 4.0, 5.0, 6.0]
    assert not any(spikes)


def test_fire_once_spikes_once_and_keeps_integrating() -> None:
    spikes, _, vs = run_trace(NeuronParams(du=1.0, v_th=1.0, reset="fire_once"), [0.5] * 4)
    assert spikes == [False, True, False, False]
    assert vs == [0.5, 1.0, 1.5, 2.0]


def test_two_phase_schedule_with_input_cut() -> None:
    # silent stage [0, 4) (no spiking, bias 0), charging from 4 (bias 1, input cut).
    # Input 1 at step 1 and 10 at step 5 (dropped: input off). u: 0 1 1 1 | 0 0 0 0
    # v: 0 1 2 3 | 4 5 6 (≥ 6 → spike at 6) 7
    params = NeuronParams(du=0.0, dv=0.0, v_th=6.0, reset="fire_once",
                          phases=(Phase(start_step=0, spiking_on=False),
                                  Phase(start_step=4, bias=1.0, input_on=False)))
    spikes, us, vs = run_trace(params, [0, 1.0, 0, 0, 0, 10.0, 0, 0])
    assert us == [0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    assert vs == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]
    assert spikes == [False] * 6 + [True, False]


def test_spiking_clamp_holds_even_above_threshold() -> None:
    # v = 2, 4 while clamped; spiking switches on at step 2 where v = 6 ≥ 1
    params = NeuronParams(du=1.0, v_th=1.0, reset="subtract",
                          phases=(Phase(start_step=0, spiking_on=False), Phase(start_step=2)))
    spikes, _, vs = run_trace(params, [2.0, 2.0, 2.0])
    assert spikes == [False, False, True]
    assert vs == [2.0, 4.0, 5.0]


def test_integer_decay_truncates_toward_zero() -> None:
    # du = 1024/4096: u ← trunc(u·3072/4096): 7 → 5 (5.25) → 3 (3.75) → 2 (2.25); v sums u
    params = NeuronParams(du=0.25, dv=0.0, v_th=1000.0)
    _, us, vs = run_trace(params, [7, 0, 0, 0], integer=True)
    assert (us, vs) == ([7, 5, 3, 2], [7, 12, 15, 17])
    _, us, vs = run_trace(params, [-7, 0, 0, 0], integer=True)  # toward zero, not floor
    assert (us, vs) == ([-7, -5, -3, -2], [-7, -12, -15, -17])
    # dv = 2048/4096: v ← trunc(v/2) + u: 5 → 2 (2.5) → 1; -5 → -2 → -1
    params = NeuronParams(du=1.0, dv=0.5, v_th=1000.0)
    assert run_trace(params, [5, 0, 0], integer=True)[2] == [5, 2, 1]
    assert run_trace(params, [-5, 0, 0], integer=True)[2] == [-5, -2, -1]


def test_integer_state_stays_int64() -> None:
    p = StepParams.from_params(NeuronParams(du=0.5, dv=0.5, v_th=3.0), 2, integer=True)
    _, state = neuron_step(NeuronState.zeros((3,), integer=True), np.array([1, 2, 9]), p, 0)
    assert state.u.dtype == state.v.dtype == np.int64
    assert state.v.tolist() == [1, 2, 6]  # 9 ≥ 3 → subtract 3


@pytest.mark.parametrize("d", [0.0, 1 / 4096, 0.25, 0.5, 4095 / 4096, 1.0])
def test_integer_decay_matches_trunc_formula(d: float) -> None:
    x = np.arange(-5000, 5001, 7, dtype=np.int64)
    big = round(d * 4096)
    expect = np.trunc(x * (4096 - big) / 4096).astype(np.int64)
    np.testing.assert_array_equal(decay(x, d, integer=True), expect)
