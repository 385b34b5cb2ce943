"""The fast conventional CFAR (radar.cfar_fast) is bit-equal to the original gathered code.

``radar.cfar._reference_noise_estimate`` / ``_reference_cfar`` run the original
implementation (radar.cfar_gather: gather every cell's training values, numpy sum /
partition / sort); every comparison here is on the bytes of the arrays, so ``-0.0`` vs
``0.0`` or a last-bit difference of a CA mean would fail. No timing here
(benchmarks/cfar_speed.py times it).
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import radar.cfar_fast as fast
import radar.cfar_gather as gather
from ir.errors import RadarConfigError
from radar.cfar import (
    _reference_cfar,
    _reference_noise_estimate,
    cfar,
    cfar_threshold,
    noise_estimate,
)
from radar.cfar_window import n_training


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _map(rng: np.random.Generator, shape: tuple[int, ...], values: str) -> np.ndarray:
    """Random map: wide-range floats, tie-heavy small integers, signed, or with signed zeros."""
    if values == "ties":
        return rng.integers(0, 4, size=shape).astype(float)
    if values == "integers":
        return rng.integers(-50, 1000, size=shape).astype(float)
    if values == "signed":
        return rng.standard_normal(shape) * np.exp(3 * rng.standard_normal(shape))
    if values == "zeros":  # signed zeros, integer-valued (summed-area tables) or not
        return rng.choice([-0.0, 0.0, 1.0, -1.0, 0.5 * rng.integers(1, 3)], size=shape)
    return rng.exponential(size=shape) * np.exp(4 * rng.standard_normal(shape))


@st.composite
def problems(draw, max_d=3):
    """A CFAR call the module accepts: 1-3-D window, batch, both kinds and edges."""
    d = draw(st.integers(1, max_d))
    guard = [draw(st.integers(0, 3 if d < 3 else 1)) for _ in range(d)]
    train = [draw(st.integers(0, 4 if d < 3 else 1)) for _ in range(d)]
    assume(any(train))
    edge = [draw(st.sampled_from(["wrap", "clip"])) for _ in range(d)]
    shape = tuple(
        draw(st.integers(2 * (g + t) + 1 if e == "wrap" else 1, 2 * (g + t) + (12 if d < 3 else 3)))
        for g, t, e in zip(guard, train, edge, strict=True)
    )
    batch = tuple(draw(st.lists(st.integers(1, 3), max_size=1)))
    values = draw(st.sampled_from(["floats", "ties", "integers", "signed", "zeros"]))
    x = _map(np.random.default_rng(draw(st.integers(0, 2**32 - 1))), batch + shape, values)
    kind = draw(st.sampled_from(["ca", "os"]))
    k = draw(st.integers(1, n_training(guard, train))) if kind == "os" else None
    alpha = draw(st.sampled_from([0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 10.0]))
    params = {"kind": kind, "guard": guard, "train": train, "k": k, "edge": edge}
    return x, params, alpha


def _check_all(x: np.ndarray, params: dict, alpha: float) -> None:
    try:
        want = _reference_noise_estimate(x, **params)
    except RadarConfigError as err:  # the same refusal from the fast path
        with pytest.raises(RadarConfigError, match=re.escape(str(err))):
            cfar(x, alpha=alpha, **params)
        return
    assert _same(noise_estimate(x, **params), want)
    assert _same(cfar_threshold(x, alpha=alpha, **params), alpha * want)
    assert _same(cfar(x, alpha=alpha, **params), _reference_cfar(x, alpha=alpha, **params))


@given(case=problems())
def test_fast_cfar_is_bit_equal_to_the_gathered_implementation(case):
    x, params, alpha = case
    _check_all(x, params, alpha)


@given(case=problems(max_d=2), block=st.integers(1, 60))
def test_bit_equal_for_every_block_size_of_the_gather(case, block):
    """Tiny gather blocks (incl. one-cell blocks, which numpy sums pairwise) are followed too."""
    x, params, alpha = case
    saved = gather._BLOCK_ELEMENTS
    gather._BLOCK_ELEMENTS = block
    try:
        _check_all(x, params, alpha)
    finally:
        gather._BLOCK_ELEMENTS = saved


@pytest.mark.parametrize("block", [1, 12 * 199, 12 * 7])
def test_one_cell_blocks_are_summed_pairwise_like_the_gather(block, monkeypatch):
    """1-D map, N = 12: a lone cell's sum (pairwise) differs from the stencil-order sum."""
    x = _map(np.random.default_rng(1), (200,), "signed")
    params = {"kind": "ca", "guard": 1, "train": 6, "edge": "clip"}
    monkeypatch.setattr(gather, "_BLOCK_ELEMENTS", block)
    want = _reference_noise_estimate(x, **params)
    assert _same(noise_estimate(x, **params), want)
    lone = fast._lone_rows((200,), 12)
    assert lone == {1: list(range(200)), 12 * 199: [199], 12 * 7: []}[block]
    monkeypatch.setattr(fast, "_lone_rows", lambda *a: [])
    differs = np.flatnonzero(noise_estimate(x, **params) != want)  # without the lone-cell rule
    assert set(differs.tolist()) <= set(lone) and (len(differs) > 0) == bool(lone)


@pytest.mark.parametrize(
    "window",
    [
        {"guard": [3, 2], "train": [8, 4], "k": 198},  # compiler.chains.DEFAULT_CFAR
        {"guard": [3, 3], "train": [4, 4], "k": 132},  # benchmarks/cfar.py
    ],
)
@pytest.mark.parametrize("values", ["floats", "ties", "integers"])
def test_full_size_chain_maps(window, values):
    """256 x 64, range clipped, Doppler wrapped, over several gather blocks, both kinds."""
    x = _map(np.random.default_rng(7), (256, 64), values)
    for kind in ("os", "ca"):
        params = window | {"kind": kind, "edge": ["clip", "wrap"]}
        if kind == "ca":
            params["k"] = None
        for alpha in (1.0, 3.0, 12.5):
            _check_all(x, params, alpha)


def test_sat_path_exact_integers_and_the_bound():
    """Integer maps use summed-area tables; beyond 2**(51-d) the stencil-order sum is used."""
    params = {"guard": (1, 2), "train": (2, 1), "edge": ("clip", "wrap")}
    small = _map(np.random.default_rng(3), (2, 40, 30), "integers")
    padded = fast._pad(small, [3, 3], params["edge"], 0.0)
    sat = fast._sat_sums(padded, params["guard"], params["train"], small.shape[1:])
    assert _same(fast.window_sums(small, **params), sat)
    huge = small * 2.0**45 + 1.0  # exact integers whose sums exceed 2**49
    kw = {"kind": "ca", "guard": [1, 2], "train": [2, 1], "edge": ["clip", "wrap"]}
    assert _same(noise_estimate(huge, **kw), _reference_noise_estimate(huge, **kw))
    assert _same(noise_estimate(small, **kw), _reference_noise_estimate(small, **kw))


@pytest.mark.filterwarnings("ignore:overflow encountered in multiply:RuntimeWarning")
def test_os_decisions_with_overflowing_threshold_and_exact_ties():
    """alpha * v = inf never detects; x == alpha * T never detects (both as the reference)."""
    rng = np.random.default_rng(5)
    x = rng.choice([1.0, 2.0, 4.0, 1e308], size=(30, 20))
    for alpha, k in ((10.0, 5), (2.0, 1), (0.5, 16), (1.0, 12)):  # N = 16
        params = {"kind": "os", "guard": [1, 1], "train": [1, 1], "k": k, "edge": ["clip", "wrap"]}
        _check_all(x, params, alpha)
