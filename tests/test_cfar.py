"""CA-/OS-CFAR (radar.cfar) against a brute-force reference; Pfa theory (radar.cfar_theory)."""

from __future__ import annotations

import itertools
import math
import tracemalloc

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from scipy.special import gammaln

import radar.cfar_gather as gather_module
from ir.errors import RadarConfigError
from radar.cfar import cfar, cfar_threshold, noise_estimate
from radar.cfar_theory import ca_alpha, ca_pfa, os_alpha, os_pfa
from radar.cfar_window import effective_k, n_training, training_counts, training_mask

# ---------------------------------------------------------------- brute-force reference


def _training_values(x_map, cell, guard, train, edge):
    """Values of the training cells of ``cell`` that exist (loops, obviously correct)."""
    values = []
    ranges = [range(-(g + t), g + t + 1) for g, t in zip(guard, train, strict=True)]
    for offset in itertools.product(*ranges):
        if all(abs(o) <= g for o, g in zip(offset, guard, strict=True)):
            continue  # guard block, including the CUT
        pos = []
        for c, o, n, e in zip(cell, offset, x_map.shape, edge, strict=True):
            p = c + o
            if e == "wrap":
                p %= n
            elif not 0 <= p < n:
                break
            pos.append(p)
        else:
            values.append(float(x_map[tuple(pos)]))
    return values


def reference_noise(x, kind, guard, train, k, edge):
    """Slow CFAR noise estimate; ``None`` if some cell has no training cell in the map."""
    x = np.asarray(x, dtype=float)
    d = len(guard)
    n_total = math.prod(2 * (g + t) + 1 for g, t in zip(guard, train, strict=True)) - math.prod(
        2 * g + 1 for g in guard
    )
    out = np.empty_like(x)
    for b in np.ndindex(x.shape[: x.ndim - d]):
        for cell in np.ndindex(x.shape[x.ndim - d :]):
            values = _training_values(x[b], cell, guard, train, edge)
            n = len(values)
            if n == 0:
                return None
            if kind == "ca":
                out[b + cell] = sum(values) / n
            else:
                k_eff = min(max(-(-k * n // n_total), 1), n)
                out[b + cell] = sorted(values, reverse=True)[k_eff - 1]
    return out


@st.composite
def cfar_cases(draw, integer_values=True):
    d = draw(st.integers(1, 2))
    guard = [draw(st.integers(0, 2)) for _ in range(d)]
    train = [draw(st.integers(0, 2)) for _ in range(d)]
    assume(any(train))
    edge = [draw(st.sampled_from(["wrap", "clip"])) for _ in range(d)]
    shape = [
        draw(st.integers(2 * (g + t) + 1 if e == "wrap" else 1, 2 * (g + t) + 3))
        for g, t, e in zip(guard, train, edge, strict=True)
    ]
    batch = draw(st.lists(st.integers(1, 2), max_size=1))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    full_shape = (*batch, *shape)
    if integer_values:  # exact sums, so CA means agree to the last bit and ties happen
        x = rng.integers(0, 6, size=full_shape).astype(float)
    else:
        x = rng.exponential(size=full_shape)
    kind = draw(st.sampled_from(["ca", "os"]))
    n_total = n_training(guard, train)
    k = draw(st.integers(1, n_total)) if kind == "os" else None
    return x, kind, guard, train, k, edge


@given(case=cfar_cases(integer_values=False))
def test_noise_estimate_matches_brute_force(case):
    x, kind, guard, train, k, edge = case
    want = reference_noise(x, kind, guard, train, k, edge)
    if want is None:
        with pytest.raises(RadarConfigError, match=r"no training cell inside the map"):
            noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)
        return
    got = noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)
    assert got.shape == x.shape and got.dtype == np.float64
    if kind == "os":
        np.testing.assert_array_equal(got, want)  # an order statistic is one of the inputs
    else:
        np.testing.assert_allclose(got, want, rtol=1e-13)


@given(case=cfar_cases(integer_values=True), alpha=st.sampled_from([0.5, 1.0, 1.25, 2.0, 3.0]))
def test_decisions_match_brute_force_exactly(case, alpha):
    x, kind, guard, train, k, edge = case
    want_noise = reference_noise(x, kind, guard, train, k, edge)
    assume(want_noise is not None)
    got_noise = noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)
    np.testing.assert_array_equal(got_noise, want_noise)
    got = cfar(x, kind=kind, guard=guard, train=train, alpha=alpha, k=k, edge=edge)
    assert got.dtype == bool
    np.testing.assert_array_equal(got, x > alpha * want_noise)


@given(case=cfar_cases(integer_values=False), block=st.integers(1, 40))
def test_blocking_does_not_change_results(case, block):
    """Tiny gather blocks (values gathered at once) give the same result as one block."""
    x, kind, guard, train, k, edge = case
    assume(reference_noise(x, kind, guard, train, k, edge) is not None)
    whole = noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)
    saved = gather_module._BLOCK_ELEMENTS
    gather_module._BLOCK_ELEMENTS = block
    try:
        blocked = noise_estimate(x, kind=kind, guard=guard, train=train, k=k, edge=edge)
    finally:
        gather_module._BLOCK_ELEMENTS = saved
    if kind == "os":
        np.testing.assert_array_equal(blocked, whole)
    else:  # numpy may order a row sum differently for other block shapes: 1-ulp effects
        np.testing.assert_allclose(blocked, whole, rtol=1e-14)


# ---------------------------------------------------------------- hand-worked numbers


def test_stencil_hand_values():
    assert training_mask(1, 2).astype(int).tolist() == [1, 1, 0, 0, 0, 1, 1]
    mask = training_mask([3, 3], [4, 4])
    assert mask.shape == (15, 15) and not mask[4:11, 4:11].any() and mask.sum() == 176
    assert n_training([3, 3], [4, 4]) == 176  # the 003 paper's 2D window
    assert n_training(6, 15) == 30  # the 003 paper's 1D window: G = 12, N = 30 in total
    assert n_training([1, 1], [1, 1]) == 16  # 5 x 5 - 3 x 3
    assert n_training([1, 1], [2, 2]) == 40  # 7 x 7 - 3 x 3
    assert n_training([0, 2], [1, 0]) == 3 * 5 - 1 * 5


def test_training_counts_hand_values():
    corner = training_counts((5, 5), guard=[1, 1], train=[1, 1], edge="clip")
    # (0, 0): window rows/cols 0..2 (3 x 3 = 9) minus guard 0..1 x 0..1 (4) = 5
    assert corner[0, 0] == 5 and corner[2, 2] == 16 and corner[0, 2] == 15 - 6
    mixed = training_counts((5, 5), guard=[1, 1], train=[1, 1], edge=["clip", "wrap"])
    assert mixed[0].tolist() == [15 - 6] * 5 and mixed[2].tolist() == [16] * 5
    assert effective_k(12, [16, 8, 3, 1], 16).tolist() == [12, 6, 3, 1]


def test_2d_hand_values_wrap():
    x = np.ones((5, 5))
    x[2, 2] = 9.0
    kw = {"guard": [1, 1], "train": [1, 1], "edge": "wrap"}
    ca = noise_estimate(x, kind="ca", **kw)
    # the CUT (2, 2) sees the all-ones ring; (0, 0)'s ring wraps onto the 9: (15 + 9) / 16
    assert ca[2, 2] == 1.0 and ca[0, 0] == 1.5 and ca[1, 1] == 1.0
    assert noise_estimate(x, kind="os", k=1, **kw)[0, 0] == 9.0
    assert noise_estimate(x, kind="os", k=2, **kw)[0, 0] == 1.0
    hits = cfar(x, kind="ca", alpha=8.0, **kw)
    assert np.argwhere(hits).tolist() == [[2, 2]]
    assert not cfar(x, kind="ca", alpha=9.0, **kw).any()  # 9 > 9 * 1 is false: strict


def test_1d_clip_renormalisation_hand_values():
    x = [4.0, 0.0, 0.0, 8.0, 0.0, 2.0]
    # guard 0, train 2: cell 0 has 2 of N = 4 training cells (cells 1, 2) -> CA 0.0;
    # cell 1 has 3 (cells 0, 2, 3) -> CA 12 / 3; cell 5 has 2 (cells 3, 4) -> CA 8 / 2
    ca = noise_estimate(x, kind="ca", guard=0, train=2)
    assert ca.tolist() == [0.0, 4.0, 12 / 4, 2 / 4, 10 / 3, 4.0]
    # OS k=2 of N=4: 3 cells -> k_eff = ceil(2*3/4) = 2, 2 cells -> k_eff = ceil(2*2/4) = 1
    # cell 1: 2nd largest of (4, 0, 8) = 4; cell 5: largest of (8, 0) = 8
    os_ = noise_estimate(x, kind="os", guard=0, train=2, k=2)
    assert os_.tolist() == [0.0, 4.0, 4.0, 0.0, 2.0, 8.0]


def test_scalar_widths_apply_to_every_axis_and_batch_axes():
    rng = np.random.default_rng(3)
    x = rng.exponential(size=(2, 6, 7))
    explicit = noise_estimate(x, kind="ca", guard=[1, 1], train=[1, 2], edge=["clip", "clip"])
    assert np.array_equal(noise_estimate(x, kind="ca", guard=1, train=[1, 2]), explicit)
    one_map = noise_estimate(x[1], kind="ca", guard=[1, 1], train=[1, 2])
    np.testing.assert_array_equal(explicit[1], one_map)
    # ints everywhere: CFAR over all axes of x (here 3D)
    all_axes = noise_estimate(x, kind="ca", guard=0, train=1)
    np.testing.assert_array_equal(
        all_axes, noise_estimate(x, kind="ca", guard=[0, 0, 0], train=[1, 1, 1])
    )
    threshold = cfar_threshold(x, kind="ca", guard=1, train=[1, 2], alpha=2.5)
    np.testing.assert_array_equal(threshold, 2.5 * explicit)


def test_large_map_memory_and_time_are_bounded():
    x = np.random.default_rng(0).exponential(size=(1000, 1000))
    tracemalloc.start()
    try:
        noise_estimate(x, kind="os", guard=[3, 3], train=[4, 4], k=132, edge=["clip", "wrap"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 300e6, f"peak {peak / 1e6:.0f} MB"


# ---------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("x", "kwargs", "match"),
    [
        (np.ones(8) + 0j, {}, r"complex; apply radar.dsp.magnitude"),
        (np.array([1.0, np.nan] * 4), {}, r"4 non-finite value\(s\) \(NaN/inf\) of 8"),
        (np.ones(8), {"kind": "go"}, r"kind='go' is not valid"),
        (np.ones(8), {"kind": "os", "k": 0}, r"k=0 must be an integer in 1\.\.4"),
        (np.ones(8), {"kind": "os", "k": 5}, r"k=5 must be an integer in 1\.\.4"),
        (np.ones(8), {"kind": "os"}, r"k=None must be an integer in 1\.\.4"),
        (np.ones(8), {"kind": "ca", "k": 2}, r"k=2 is only used by kind='os'"),
        (np.ones(8), {"alpha": 0.0}, r"alpha=0.0 must be finite and > 0"),
        (np.ones(8), {"alpha": -2.0}, r"alpha=-2.0 must be finite and > 0"),
        (np.ones(8), {"alpha": np.nan}, r"alpha=nan must be finite and > 0"),
        (np.ones(4), {"edge": "wrap"}, r"axis 0 \(length 4\).*= 5 <= 4"),
        (np.ones(8), {"edge": "mirror"}, r"'mirror' is not an edge mode"),
        (np.ones(8), {"edge": None}, r"edge=None must be 'wrap', 'clip' or a list"),
        (np.ones(8), {"guard": -1}, r"guard=-1: widths must be non-negative"),
        (np.ones(8), {"train": 0}, r"train=0 leaves no training cells"),
        (np.ones(8), {"guard": [1, 1], "train": [1]}, r"different numbers of axes \[1, 2\]"),
        (np.ones(8), {"guard": [1, 1], "train": [1, 1]}, r"2-D window but x has only 1"),
        (np.ones(2), {"guard": 2}, r"cell \(0,\) has no training cell inside the map"),
    ],
)
def test_cfar_errors(x, kwargs, match):
    params = {"kind": "ca", "guard": 0, "train": 2, "alpha": 1.0, "edge": "clip"} | kwargs
    with pytest.raises(RadarConfigError, match=match):
        cfar(x, **params)


# ---------------------------------------------------------------- Pfa theory


def test_theory_hand_values():
    assert ca_pfa(1.0, 1) == 0.5 and ca_pfa(2.0, 2) == pytest.approx(0.25, rel=1e-15)
    assert ca_alpha(1e-3, 16) == pytest.approx(8.6388, abs=5e-5)  # NOTES.md section 2
    # n=2: max (k=1, m=2): 2/3 * 1/2 at alpha=1; min (k=2, m=1): 2/(2+2) at alpha=2
    assert os_pfa(1.0, 2, 1) == pytest.approx(1 / 3, rel=1e-15)
    assert os_pfa(2.0, 2, 2) == pytest.approx(0.5, rel=1e-15)
    assert os_alpha(0.5, 2, 2) == pytest.approx(2.0, rel=1e-12)


def test_notes_os_example_is_kth_smallest():
    """NOTES.md: N=16, 'k=12' (k-th smallest), Pfa=1e-3 -> 7.4215; ours is k = 16 - 12 + 1 = 5."""
    k_smallest = 12
    alpha = os_alpha(1e-3, 16, 16 - k_smallest + 1)
    assert alpha == pytest.approx(7.42141131, abs=1e-7)  # NOTES rounds this to 7.4215
    assert abs(alpha - 7.4215) < 1e-4
    assert os_alpha(1e-3, 16, k_smallest) == pytest.approx(41.4669, abs=1e-3)  # not that one


@given(
    n=st.integers(1, 200),
    k_frac=st.floats(0, 1),
    log_pfa=st.floats(-12, -0.01),
)
def test_theory_round_trips_and_gamma_form(n, k_frac, log_pfa):
    pfa = 10.0**log_pfa
    k = 1 + int(k_frac * (n - 1))
    a_ca, a_os = ca_alpha(pfa, n), os_alpha(pfa, n, k)
    assert ca_pfa(a_ca, n) == pytest.approx(pfa, rel=1e-10)
    assert os_pfa(a_os, n, k) == pytest.approx(pfa, rel=1e-10)
    # independent closed form: m-th smallest, Pfa = G(n+1) G(n-m+1+a) / (G(n-m+1) G(n+1+a))
    m = n - k + 1
    log_gamma_form = gammaln(n + 1) + gammaln(n - m + 1 + a_os) - gammaln(n - m + 1)
    log_gamma_form -= gammaln(n + 1 + a_os)
    # (gammaln of alpha ~ 1e12 loses ~eps * gammaln digits, so the bound scales with it)
    tolerance = 1e-13 * (abs(gammaln(n + 1 + a_os)) + 1.0)
    assert log_gamma_form == pytest.approx(math.log(pfa), abs=tolerance)
    if k < n:  # a smaller order statistic (larger k) needs a larger factor
        assert os_alpha(pfa, n, k + 1) > a_os


@given(alpha=st.floats(1e-3, 1e6))
def test_os_with_one_cell_is_ca(alpha):
    assert os_pfa(alpha, 1, 1) == pytest.approx(ca_pfa(alpha, 1), rel=1e-14)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: ca_alpha(0.0, 16), r"pfa=0.0 is outside the open interval \(0, 1\)"),
        (lambda: os_alpha(1.0, 16, 4), r"pfa=1.0 is outside"),
        (lambda: ca_alpha(np.nan, 16), r"pfa=nan is outside"),
        (lambda: os_pfa(1.0, 16, 17), r"k=17 must be an integer in 1\.\.16"),
        (lambda: os_alpha(1e-3, 16, 0), r"k=0 must be an integer in 1\.\.16"),
        (lambda: ca_pfa(0.0, 16), r"alpha=0.0 must be finite and > 0"),
        (lambda: os_pfa(np.inf, 16, 3), r"alpha=inf must be finite"),
        (lambda: ca_pfa(1.0, 0), r"n=0 must be an integer >= 1"),
        (lambda: os_alpha(5e-324, 1, 1), r"beyond the float range"),
    ],
)
def test_theory_errors(call, match):
    with pytest.raises(RadarConfigError, match=match):
        call()


# ---------------------------------------------------------------- measured false-alarm rates

PFA = 1e-3


@pytest.mark.parametrize(
    ("kind", "guard", "train", "k"),
    [
        ("ca", [1], [8], None),  # 1D, N = 16
        ("os", [1], [8], 12),  # 12th largest = 5th smallest
        ("os", [1], [8], 5),  # 5th largest = 12th smallest (the usual ~3N/4-th smallest)
        ("ca", [1, 1], [1, 1], None),  # 2D 5 x 5 - 3 x 3, N = 16
        ("os", [1, 1], [1, 1], 12),
        ("os", [1, 1], [1, 1], 5),
    ],
)
def test_false_alarm_rate_matches_theory(kind, guard, train, k):
    n = n_training(guard, train)
    alpha = ca_alpha(PFA, n) if kind == "ca" else os_alpha(PFA, n, k)
    x = np.random.default_rng(0).exponential(size=(1000, 1000))  # i.i.d. square-law noise
    hits = cfar(x, kind=kind, guard=guard, train=train, alpha=alpha, k=k, edge="wrap")
    measured = hits.mean()
    assert abs(measured - PFA) <= 3 * math.sqrt(PFA / x.size), f"measured Pfa {measured:.3e}"
