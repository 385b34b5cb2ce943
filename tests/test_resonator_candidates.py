"""The renormalised resonator's candidate errors, with what depends on the step coefficient
alone computed once, equal ``weight_errors`` on the broadcast candidates bit for bit, and
the coefficients chosen are the same (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from compiler.lowering.resonator_fixed import (
    BLOCK_GROWTH,
    Renorm,
    _candidate_errors,
    _factors,
    _lattice,
    renormalised_coefficients,
    weight_errors,
)


def _reference(theta, rho, bits, n_steps, block):
    """``renormalised_coefficients`` as it was: every candidate broadcast to (E, P, K)."""
    one, k = 2.0 ** bits, theta.size
    c, s = _lattice(one * rho * np.cos(theta), one * rho * np.sin(theta), 3)
    a_hat = (c + 1j * s) / one
    target = (rho * np.exp(1j * theta)) ** block / a_hat ** (block - 1) * one
    ce, se = _lattice(target.real, target.imag, 1)
    ce, se = np.concatenate([ce, c[None]]), np.concatenate([se, s[None]])
    th = np.broadcast_to(theta, ce.shape)
    cand = Renorm(np.broadcast_to(c, ce.shape), np.broadcast_to(s, ce.shape), ce, se, block)
    cost = weight_errors(cand.c, cand.s, th, n_steps, rho=rho, bits=bits, renorm=cand)
    a_rel, e_rel, _ = _factors(cand.c, cand.s, th, bits, cand, n_steps)
    bad = ((np.maximum(np.abs(cand.c), np.abs(cand.s)) > one)
           | (np.maximum(np.abs(ce), np.abs(se)) > one)
           | (np.abs(a_hat)[None] ** (block - 1) > BLOCK_GROWTH)
           | (np.abs(a_rel ** (block - 1) * e_rel) > rho ** block * (1 + 1e-12)))
    raw = cost.copy()
    cost[bad | ~np.isfinite(cost)] = np.inf
    best = np.argmin(cost.reshape(-1, k), axis=0)
    i_end, i_step = np.unravel_index(best, cost.shape[:2])
    cols = np.arange(k)
    return (Renorm(c[i_step, cols], s[i_step, cols], ce[i_end, i_step, cols],
                   se[i_end, i_step, cols], block), raw, (c, s, ce, se))


@settings(max_examples=60, deadline=None)
@given(k=st.integers(1, 40), seed=st.integers(0, 2 ** 32 - 1),
       rho=st.sampled_from([1.0, 0.999, 0.97, 0.9]), bits=st.sampled_from([6, 8, 12, 16]),
       n_steps=st.sampled_from([8, 16, 37, 64, 100, 256]), block=st.integers(2, 64))
def test_candidate_errors_equal_weight_errors_on_the_broadcast_candidates(k, seed, rho, bits,
                                                                           n_steps, block):
    if block > n_steps:
        block = n_steps
    rng = np.random.default_rng(seed)
    theta = np.sort(rng.uniform(0, 2 * np.pi, k))
    theta[: k // 4] = 2 * np.pi * np.arange(k // 4) / max(k, 1)  # exact DFT bins too
    want, raw, (c, s, ce, se) = _reference(theta, rho, bits, n_steps, block)
    cost, a_rel, e_rel = _candidate_errors(c, s, ce, se, theta, n_steps, rho, bits, block)
    assert cost.shape == raw.shape
    assert cost.tobytes() == raw.tobytes()  # bit for bit, nan and inf included
    got = renormalised_coefficients(theta, rho, bits, n_steps=n_steps, block=block)
    for g, w in zip(got, want, strict=True):
        assert np.asarray(g).tobytes() == np.asarray(w).tobytes()


def test_a_hand_worked_case():
    r = renormalised_coefficients(np.array([0.0]), 1.0, 12, n_steps=64, block=16)
    assert (r.c.tolist(), r.s.tolist(), r.c_end.tolist(), r.block) == ([4096.0], [0.0],
                                                                       [4096.0], 16)
