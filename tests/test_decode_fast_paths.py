"""The read-out's in-place forms equal their plain formulas bit for bit: ``combine_parts``
(one complex buffer), the ``membrane`` decoder (one float buffer, cached gains) and the
state-overflow count (skipped when the extremes are within the limit)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.decoding import DECODERS, _neuron_gains
from backends.reference.simulate import _overflow
from compiler.snn.coding import Decoder
from compiler.snn.parts import combine_parts

_SPECIAL = [0.0, -0.0, 1.5, -2.25, 5e-324, -5e-324, np.inf, -np.inf, np.nan, 1e308, -1e308]


def _draw(rng, shape, special=True):
    x = rng.normal(0, 50, shape)
    if special:
        pick = rng.random(shape) < 0.3
        x[pick] = rng.choice(_SPECIAL, int(pick.sum()))
    return x


@settings(max_examples=80, deadline=None)
@given(shape=st.lists(st.integers(0, 4), min_size=0, max_size=3), seed=st.integers(0, 2 ** 16),
       strided=st.booleans())
def test_combine_re_im_signed_is_the_plain_formula(shape, seed, strided):
    rng = np.random.default_rng(seed)
    y = _draw(rng, (*shape, 8 if strided else 4))
    y = y[..., ::2] if strided else y
    with np.errstate(invalid="ignore", over="ignore"):
        want = (y[..., 0] - y[..., 1]) + 1j * (y[..., 2] - y[..., 3])
        got = combine_parts(y, "re_im_signed")
    assert got.dtype == want.dtype and got.shape == want.shape
    g, w = (np.atleast_1d(a).view(np.float64) for a in (got, want))  # (re, im) floats
    np.testing.assert_array_equal(np.isnan(g), np.isnan(w))
    ok = ~np.isnan(w)  # NaN payload bits follow the compiled loops' operand order: not compared
    assert g[ok].tobytes() == w[ok].tobytes()  # signed zeros included


@settings(max_examples=60, deadline=None)
@given(sizes=st.lists(st.integers(1, 5), min_size=1, max_size=3), frames=st.integers(1, 3),
       integer=st.booleans(), gained=st.booleans(), seed=st.integers(0, 2 ** 16))
def test_membrane_decoder_is_the_plain_formula(sizes, frames, integer, gained, seed):
    rng = np.random.default_rng(seed)
    shape = {f"a{i}": n for i, n in enumerate(sizes)}
    size = int(np.prod(sizes))
    v = (rng.integers(-2 ** 40, 2 ** 40, (frames, size)) if integer
         else _draw(rng, (frames, size), special=False))
    dec = Decoder(port="y", population="p", kind="membrane", scale=float(rng.normal()),
                  offset=float(rng.choice([0.0, -0.0, rng.normal()])),
                  **({"gain_axis": "a0", "gains": tuple(rng.uniform(0.1, 3.0, sizes[0]))}
                     if gained else {}))
    act = SimpleNamespace(membrane={"p": v})
    gains = _neuron_gains(dec, tuple(shape.items()))
    want = (dec.scale * v.astype(np.float64) + dec.offset) / dec.neuron_gains(shape)
    got = DECODERS["membrane"](dec, act, "p", gains)
    assert got.tobytes() == want.tobytes()
    assert _neuron_gains(dec, tuple(shape.items())) is gains  # kept for the next frames
    if gained:
        assert not gains.flags.writeable


@settings(max_examples=80, deadline=None)
@given(n=st.integers(0, 30), limit=st.integers(0, 2 ** 20), integer=st.booleans(),
       seed=st.integers(0, 2 ** 16))
def test_overflow_count_is_the_plain_count(n, limit, integer, seed):
    rng = np.random.default_rng(seed)
    v = (rng.integers(-2 ** 21, 2 ** 21, (1, n)) if integer
         else rng.normal(0, 2.0 ** rng.integers(0, 22), (1, n)))
    if not integer and n:
        v[0, rng.random(n) < 0.2] = np.nan
    plan = SimpleNamespace(state_limit=limit)
    act = SimpleNamespace(overflow={}, membrane={"p": v, "q": -v})
    want = {pid: c for pid, m in act.membrane.items()
            if (c := int(np.count_nonzero(np.abs(m) > limit)))}
    assert _overflow(plan, act) == want


def test_overflow_of_the_most_negative_integer_is_the_plain_count():
    v = np.array([[np.iinfo(np.int64).min, 3]])  # |min| wraps to min: not counted
    act = SimpleNamespace(overflow={}, membrane={"p": v})
    assert _overflow(SimpleNamespace(state_limit=5), act) == {}
    assert _overflow(SimpleNamespace(state_limit=2), act) == {"p": 1}
