r"""A hand-built time-coded 16-point DFT (S-FT) against ``np.fft``, in both engines.

Construction (López-Randulfe et al. 2022): inputs ``x_j ∈ [0, 1]`` spike once at
``t_j = rint((1 - x_j)·T)``; one two-stage ramp neuron (``du = dv = 0``,
fire-once) per output bin and part, weights ``W = [cos; -sin]``.

* silent stage ``[0, T)``: ``V = Σ_j W_kj (T - t_j) = T·Σ_j W_kj x̂_j`` with
  ``x̂_j = 1 - t_j/T``, ``|x̂_j - x_j| ≤ 1/(2T)``;
* charging stage ``[T, 2T)``: input cut, bias ``b = 2·v_th/T``; the neuron
  fires at ``t_s = T - 1 + max(1, ⌈(v_th - V)/b⌉)``, within ``[t* - 1, t*]`` of the
  ideal ``t* = T + (v_th - V)/b``.

Decoding ``y = (2 v_th / T²)·(1.5T - 1/2 - t_s)`` gives ``V/T ± v_th/T²``, so

.. math:: |y_k - X_k| \le v_{th}/T^2 + \tfrac{1}{2T} \textstyle\sum_j |W_{kj}|

per real and imaginary part.  With ``v_th = N·T`` every ``|V| ≤ v_th`` fires
inside the window and the bias ``2N`` is an integer (dyadic).
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import simulate
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    SpikingNetwork,
)

N, T = 16, 128
V_TH = float(N * T)


def dft_weights() -> np.ndarray:
    """``(N, 2N)``: column ``2k`` is ``cos(2πkj/N)``, column ``2k+1`` is ``-sin(2πkj/N)``."""
    angle = 2 * np.pi * np.outer(np.arange(N), np.arange(N)) / N
    return np.stack([np.cos(angle), -np.sin(angle)], axis=-1).reshape(N, 2 * N)


def sft_network(w: np.ndarray) -> SpikingNetwork:
    params = NeuronParams(du=0.0, dv=0.0, v_th=V_TH, reset="fire_once",
                          phases=(Phase(start_step=0, spiking_on=False),
                                  Phase(start_step=T, bias=2 * V_TH / T, input_on=False)))
    return SpikingNetwork(
        name="sft16", n_steps=2 * T,
        populations=[Population(id="x", shape={"sample": N}, source=True),
                     Population(id="y", shape={"bin": N, "part": 2}, params=params)],
        projections=[MatrixProjection(id="dft", source="x", target="y", contract=("sample",),
                                      produce=("bin", "part"), weights=w)],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=T, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="X", population="y", kind="spike_time", combine="re_im",
                          scale=2 * V_TH / T**2, t_ref=1.5 * T - 0.5, missing=np.nan)])


def bound(w: np.ndarray) -> np.ndarray:
    """Per bin and part, the error bound of the module docstring, shape ``(N, 2)``."""
    return V_TH / T**2 + np.abs(w).sum(axis=0).reshape(N, 2) / (2 * T)


@pytest.mark.parametrize("mode", ["step", "closed"])
def test_sft_matches_fft_within_bound(mode: str) -> None:
    x = np.random.default_rng(3).random((5, N))
    w = dft_weights()
    r = simulate(sft_network(w), {"x": x}, mode=mode)
    got = r.outputs["X"]
    want = np.fft.fft(x, axis=-1)
    assert got.shape == (5, N) and not np.isnan(got).any()  # every neuron fired
    err = np.stack([np.abs(got.real - want.real), np.abs(got.imag - want.imag)], axis=-1)
    assert np.all(err <= bound(w) + 1e-9)
    assert err.max() > 0.1 * bound(w).min()  # the bound is not vacuous
    assert r.spike_counts["y"] == 5 * 2 * N


def test_sft_quantized_weights_identical_in_both_modes() -> None:
    """Weights on a 2**-8 grid: every sum is exact, so the engines agree bit for bit."""
    w = np.round(dft_weights() * 256) / 256
    x = np.random.default_rng(4).random((4, N))
    step = simulate(sft_network(w), {"x": x}, mode="step")
    closed = simulate(sft_network(w), {"x": x}, mode="closed")
    np.testing.assert_array_equal(step.first_spike_steps["y"], closed.first_spike_steps["y"])
    np.testing.assert_array_equal(step.outputs["X"], closed.outputs["X"])
    want = x @ w  # the DFT with the quantized weights, as (re, im) per bin
    got = np.stack([closed.outputs["X"].real, closed.outputs["X"].imag], axis=-1)
    assert np.all(np.abs(got.reshape(4, 2 * N) - want) <= bound(w).ravel() + 1e-12)


def test_sft_spike_steps_hand_worked() -> None:
    """x = e_0 (one input at full scale, spike at step 0): V = W_k0·T = T for Re, 0 for Im.

    Charging from step T = 128 with b = 32 and v_th = 2048, t_s = T - 1 + ⌈(v_th - V)/b⌉:
    Re: V = 128, ⌈1920/32⌉ = 60 → t_s = 187.  Im: V = 0, ⌈2048/32⌉ = 64 → t_s = 191.
    """
    x = np.zeros(N)
    x[0] = 1.0
    r = simulate(sft_network(dft_weights()), {"x": x}, mode="closed")
    assert r.first_spike_steps["y"][0, :, 0].tolist() == [187] * N
    assert r.first_spike_steps["y"][0, :, 1].tolist() == [191] * N
