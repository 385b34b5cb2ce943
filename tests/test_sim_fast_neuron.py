"""LiveNeurons (the step engine's in-place neuron update) against neuron_step, bit for bit.

``neuron_step`` is the executable definition of the update; ``LiveNeurons`` skips
operations that cannot change a bit (decays by ``1.0``, additions of ``+0.0`` to
arrays that hold no ``-0.0``, threshold tests at an unchanged membrane).  These
tests drive both with the same currents on random parameters — leaky and
non-leaky, every reset, phase schedules, arbitrary (non-dyadic) floats, negative
zeros in biases, resets and currents — and compare every bit of ``u``, ``v`` and
the spikes after every step.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.live_neurons import LiveNeurons
from backends.reference.neuron import NeuronState, StepParams, neuron_step
from compiler.snn import NeuronParams, Phase


def _bits(a: np.ndarray) -> np.ndarray:
    """The raw bits of an array (so ``-0.0`` and ``+0.0`` differ)."""
    return a.view(np.int64) if a.dtype == np.float64 else a


def _add(contribution: tuple[np.ndarray, np.ndarray], out: np.ndarray) -> None:
    """Add a contribution to the entries it reaches only, as the in-place deliveries do."""
    reach, values = contribution
    out[reach] += values[reach]


def _dense(contribution: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The contribution as the dense current a delivery returns (+0 where it does not reach)."""
    reach, values = contribution
    return np.where(reach, values, np.zeros_like(values))


def random_params(rng: np.random.Generator, n_steps: int, integer: bool) -> NeuronParams:
    """Random parameters: decays 0, 1 or in between, any reset, up to three phases."""
    def number(scale: float) -> float:
        if integer:
            return float(rng.integers(-3, 6))
        pick = rng.random()
        if pick < 0.15:
            return -0.0
        if pick < 0.3:
            return 0.0
        return float(rng.normal(0.0, scale))

    decays = [0.0, 1.0, 0.5, 1 / 4096, 1000 / 4096] if integer else [0.0, 1.0, 0.3, 1e-3]
    starts = sorted({0, *rng.integers(1, n_steps + 1, size=2).tolist()})
    phases = tuple(Phase(start_step=s, bias=number(0.5), input_on=bool(rng.random() < 0.75),
                         spiking_on=bool(rng.random() < 0.75)) for s in starts)
    return NeuronParams(du=float(rng.choice(decays)), dv=float(rng.choice(decays)),
                        v_th=float(rng.integers(1, 8)) if integer else abs(number(1.0)) + 0.1,
                        reset=str(rng.choice(["value", "subtract", "fire_once"])),
                        v_reset=number(0.5), phases=phases)


def random_currents(rng: np.random.Generator, n: int, integer: bool) -> list[tuple]:
    """0 to 3 contributions ``(reach, values)``; floats include ±0 and subnormals."""
    out = []
    for _ in range(int(rng.choice([0, 1, 1, 2, 3]))):
        if integer:
            c = rng.integers(-4, 5, size=n)
        else:
            c = rng.normal(0.0, 1.0, size=n) * 10.0 ** rng.integers(-322, 3, size=n)
            c[rng.random(n) < 0.3] = 0.0
            c[rng.random(n) < 0.2] = -0.0
        out.append((rng.random(n) < 0.7, c))
    return out


def run_both(seed: int, integer: bool) -> None:
    rng = np.random.default_rng(seed)
    n_steps, n = int(rng.integers(1, 25)), int(rng.integers(1, 7))
    params = StepParams.from_params(random_params(rng, n_steps, integer), n_steps, integer)
    live = LiveNeurons(params, n)
    state = NeuronState.zeros((n,), integer)
    for t in range(n_steps):
        currents = random_currents(rng, n, integer)
        total = 0
        for c in currents:  # the dense sum of the reference: ((0 + I_1) + I_2) + ...
            total = total + _dense(c)
        spikes, state = neuron_step(state, total, params, t)
        fired = live.step(t, currents, _add)
        np.testing.assert_array_equal(fired, np.flatnonzero(spikes), err_msg=f"t={t}")
        np.testing.assert_array_equal(_bits(live.u), _bits(state.u), err_msg=f"u, t={t}")
        np.testing.assert_array_equal(_bits(live.v), _bits(state.v), err_msg=f"v, t={t}")


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_live_neurons_match_neuron_step_float64(seed: int) -> None:
    run_both(seed, integer=False)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_live_neurons_match_neuron_step_int64(seed: int) -> None:
    run_both(seed, integer=True)


def test_hand_worked_ramp_then_charge() -> None:
    """A ramp neuron (du = dv = 0): silent stage then charging, worked by hand.

    Inputs 1.0 at step 0 and 0.5 at step 1 (spiking off, no bias): u = 1, 1.5, 1.5;
    v = 1, 2.5, 4.  Charging from step 3 with bias 2 (input off, u = 0): v = 6, 8, 10;
    threshold 7.5 is first reached at step 4; fire-once keeps v growing.
    """
    p = StepParams.from_params(NeuronParams(
        du=0.0, dv=0.0, v_th=7.5, reset="fire_once",
        phases=(Phase(start_step=0, spiking_on=False),
                Phase(start_step=3, bias=2.0, input_on=False))), n_steps=6)
    live = LiveNeurons(p, 1)
    on = np.ones(1, bool)
    drive = {0: [(on, np.array([1.0]))], 1: [(on, np.array([0.5]))]}
    trace = [(live.step(t, drive.get(t, []), _add).tolist(), float(live.u[0]), float(live.v[0]))
             for t in range(6)]
    assert trace == [([], 1.0, 1.0), ([], 1.5, 2.5), ([], 1.5, 4.0),
                     ([], 0.0, 6.0), ([0], 0.0, 8.0), ([], 0.0, 10.0)]


def test_unchanged_membrane_skips_the_test_but_keeps_value_resets() -> None:
    """Reset to a value at or above threshold fires again at the unchanged membrane.

    v_th = 1, v_reset = 2, no input or bias: the neuron driven to 1 at step 0
    fires, is reset to 2, and fires at every later step (v stays 2); a fire-once
    neuron at the same membrane fires once only.
    """
    value = StepParams.from_params(NeuronParams(du=1.0, v_th=1.0, v_reset=2.0, reset="value"),
                                   n_steps=4)
    once = StepParams.from_params(NeuronParams(du=1.0, v_th=1.0, reset="fire_once"), n_steps=4)
    for params, want in ((value, [[0], [0], [0], [0]]), (once, [[0], [], [], []])):
        live = LiveNeurons(params, 1)
        got = [live.step(t, [(np.ones(1, bool), np.array([1.0]))] if t == 0 else [],
                         _add).tolist() for t in range(4)]
        assert got == want


def test_negative_zero_reset_is_kept_then_cleared_as_by_neuron_step() -> None:
    """v_reset = -0.0: the reset stores -0.0; the next step adds u + b = +0.0, giving +0.0.

    Current 1.0 at step 0 (du = 1) reaches v_th = 1: spike, v = -0.0.  Step 1 has
    no input: u = 0.0·1 + 0 = 0, v = -0.0 + (0 + 0) = +0.0 — the sign bit clears,
    in both implementations.
    """
    p = StepParams.from_params(NeuronParams(du=1.0, v_th=1.0, v_reset=-0.0, reset="value"),
                               n_steps=2)
    live, state = LiveNeurons(p, 1), NeuronState.zeros((1,))
    signs = []
    for t, c in enumerate([np.array([1.0]), np.array([0.0])]):
        _, state = neuron_step(state, 0 + c, p, t)
        live.step(t, [(np.ones(1, bool), c)] if t == 0 else [], _add)
        signs.append((bool(np.signbit(live.v[0])), bool(np.signbit(state.v[0]))))
    assert signs == [(True, True), (False, False)]
