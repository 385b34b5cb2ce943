"""Periodic renormalisation of fixed-point resonators (issue 22): the closed-form drift bounds
equal the products of the actual coefficient schedule, the compiler keeps a 1024-point layer
within the stated bound at the chip's 12 bits, and the error it measures follows the bound."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.lowering.resonator import ResonatorDriftWarning
from compiler.lowering.resonator_fixed import (
    bin_angles,
    bin_gains,
    drift_report,
    fixed_coefficients,
    renormalised_coefficients,
    weight_errors,
)
from compiler.snn.resonator import Phase, ResonatorParams
from ir import Graph
from ir.errors import CompileError


def _products(c, s, c_end, s_end, bits, n, block):
    """``P_n`` per sample and bin by multiplying the schedule's coefficients out."""
    one = 2.0 ** bits
    a, e = (c + 1j * s) / one, (c_end + 1j * s_end) / one
    out = np.empty((n, a.size), complex)
    p = np.ones(a.size, complex)
    for t in range(n - 1, -1, -1):
        p = p * (e if block and (n - 1 - t) % block == 0 else a)
        out[t] = p
    return out


@settings(max_examples=40, deadline=None)
@given(n=st.integers(4, 300), bits=st.integers(6, 14), block=st.integers(0, 40),
       rho=st.sampled_from([1.0, 0.97]), seed=st.integers(0, 2 ** 16))
@example(n=34, bits=13, block=7, rho=0.97, seed=39848)  # |â|² within 1e-10 of ρ²: 1 − q^n cancelled
def test_closed_form_bounds_equal_the_multiplied_out_schedule(n, bits, block, rho, seed):
    theta = np.random.default_rng(seed).uniform(-np.pi, np.pi, 5)
    block = block if 2 <= block <= n else 0
    if block:
        r = renormalised_coefficients(theta, rho, bits, n_steps=n, block=block)
    else:
        c, s = fixed_coefficients(theta, rho, bits, n_steps=n)
        r = None
    c, s = (r.c, r.s) if r else (c, s)
    ce, se = (r.c_end, r.s_end) if r else (c, s)
    p = _products(c, s, ce, se, bits, n, block)
    ideal = (rho * np.exp(1j * theta))[None] ** (n - np.arange(n))[:, None]
    eps = p / ideal - 1
    # compared squared: the closed form's last step, Σ|P|²/N − 2Re ΣP/N + 1, is exact to
    # about 1e-15, its square root then only to ~1e-8 near zero
    np.testing.assert_allclose(weight_errors(c, s, theta, n, rho=rho, bits=bits, renorm=r) ** 2,
                               np.mean(np.abs(eps) ** 2, axis=0), rtol=1e-7, atol=1e-13)
    own = np.sum(p * np.exp(-1j * theta)[None] ** (n - np.arange(n))[:, None], axis=0)
    np.testing.assert_allclose(bin_gains(c, s, theta, n, rho=rho, bits=bits, renorm=r),
                               own / np.sum(rho ** np.arange(1, n + 1)), atol=1e-9)
    rep = drift_report(c, s, theta, n_steps=n, rho=rho, bits=bits, full_state=0, renorm=r)
    drift = np.unwrap(np.angle(p / ideal)[::-1], axis=0)  # accumulated from the last step
    assert rep["phase_drift_rad"] == pytest.approx(np.max(np.abs(drift)), abs=1e-9)
    assert rep["renorm_steps"] == block


def test_every_block_keeps_the_state_bounded_and_the_format():
    theta = bin_angles(np.arange(512), 1024)
    for block in (4, 32, 256):
        r = renormalised_coefficients(theta, 1.0, 12, n_steps=1024, block=block)
        assert max(np.abs(np.concatenate([r.c, r.s, r.c_end, r.s_end]))) <= 4096
        # ResonatorParams checks |â|^(M−1)|ĉ| <= 1 itself
        ResonatorParams(axis="k", cos=tuple(r.c), sin=tuple(r.s), coef_bits=12,
                        renorm_steps=block, cos_end=tuple(r.c_end), sin_end=tuple(r.s_end),
                        phases=(Phase(start_step=0, spiking_on=False),))


def _ti(n: int):
    from radar.loaders import load_ti_chirps

    chirps, _ = load_ti_chirps()
    return chirps[:2, :n].astype(np.float64)


def _run(x: np.ndarray, **options):
    g = Graph.from_dict({"name": "ti", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": x.shape[0], "sample": x.shape[1]}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        p = compile_graph(g, "loihi2", motifs={"f": "resonator"}, calibration_inputs={"x": x},
                          options={"resonator_readout": "graded", **options})
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    ref = np.fft.fft(x, axis=1)[:, : x.shape[1] // 2]
    err = float(np.sqrt(np.mean(np.abs(y - ref) ** 2)) / np.abs(ref).max())
    drifted = [w for w in caught if issubclass(w.category, ResonatorDriftWarning)]
    return p.networks[0].meta["resonator"]["f"], err, drifted


def test_a_1024_point_layer_stays_within_the_bound_at_the_chips_12_bits():
    x = _ti(1024)
    off, err_off, warned_off = _run(x, resonator_renorm="off")
    auto, err_auto, warned_auto = _run(x)
    assert off["renorm_steps"] == 0 and off["bound"] > 0.1 and warned_off
    assert auto["coef_bits"] == 12 and auto["renorm_steps"] >= 2
    assert auto["bound"] <= 0.01 and not warned_auto
    # the measured error (relative to the largest bin) is within the bound, and far below off
    assert err_auto <= auto["bound"] and err_auto < err_off / 4


def test_a_fixed_block_length_is_used_and_a_too_long_one_refused():
    x = _ti(64)
    fixed, _, _ = _run(x, resonator_renorm=8)
    assert fixed["renorm_steps"] == 8
    with pytest.raises(CompileError, match=r"node 'f': resonator_renorm=65 is longer than the "
                                           r"64 input steps"):
        _run(x, resonator_renorm=65)
