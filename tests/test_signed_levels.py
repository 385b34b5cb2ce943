"""Levels of complex values straight from their components (``StreamCode.signed_level_rows``,
the encoder's fast path) equal the levels of their four ``re_im_signed`` parts."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.encoding import TRAINS, encode_inputs
from compiler.snn import Encoder, Population, SpikingNetwork
from compiler.snn.parts import split_values
from compiler.snn.stream import StreamCode

_SPECIAL = [0.0, -0.0, 5e-324, -5e-324, 1e-300, -1e-300]


def _values(rng, shape, x_max, bound):
    """Components in ``[−1.2·bound, 1.2·bound]`` with signed zeros, tiny values, the clip
    edge ``x_max`` and the bound itself."""
    re, im = (rng.uniform(-1.2 * bound, 1.2 * bound, shape) for _ in range(2))
    for c in (re, im):
        pick = rng.random(shape) < 0.25
        c[pick] = rng.choice(_SPECIAL + [x_max, -x_max, bound, -bound], int(pick.sum()))
    x = np.empty(shape, np.complex128)
    x.real, x.imag = re, im
    return x


@settings(max_examples=80, deadline=None)
@given(frames=st.integers(1, 2), pre=st.integers(1, 3), length=st.integers(1, 6),
       inner=st.integers(1, 3), bits=st.integers(1, 20), x_max=st.sampled_from([1.0, 0.3, 7.5]),
       gains=st.sampled_from(["none", "positive", "zeros"]), seed=st.integers(0, 2 ** 16))
def test_signed_levels_are_the_levels_of_the_parts(frames, pre, length, inner, bits, x_max,
                                                  gains, seed):
    rng = np.random.default_rng(seed)
    g = {"none": (), "positive": tuple(rng.uniform(0.1, 1.5, length)),
         "zeros": tuple(rng.choice([0.0, 0.5, 1.0], length))}[gains]
    code = StreamCode(axis="n", length=length, inner=4 * inner, bits=bits, x_max=x_max, gains=g)
    x = _values(rng, (frames, pre, length, inner), x_max, code.bound())
    want = code.level_rows(split_values(x, "re_im_signed").reshape(frames, -1))
    got = code.signed_level_rows(x)
    assert got.dtype == want.dtype and got.shape == want.shape
    np.testing.assert_array_equal(got, want)


def test_signed_levels_decline_what_they_do_not_cover():
    code = StreamCode(axis="n", length=2, inner=4, bits=3, x_max=1.0, gains=(1.0, -0.5))
    assert code.signed_level_rows(np.ones((1, 2), np.complex128)) is None  # a negative gain
    code = StreamCode(axis="n", length=2, inner=2, bits=3, x_max=1.0)
    assert code.signed_level_rows(np.ones((1, 2), np.complex128)) is None  # not 4 parts
    code = StreamCode(axis="n", length=2, inner=4, bits=3, x_max=1.0)
    assert code.signed_level_rows(np.ones((1, 2), np.complex64)) is None


@settings(max_examples=40, deadline=None)
@given(length=st.integers(1, 5), rows=st.integers(1, 3), over=st.booleans(),
       strided=st.booleans(), seed=st.integers(0, 2 ** 16))
def test_encoder_fast_path_gives_the_parts_path_train(length, rows, over, strided, seed):
    rng = np.random.default_rng(seed)
    code = StreamCode(axis="n", length=length, inner=4, bits=6, x_max=1.0, start_step=1,
                      gains=tuple(rng.uniform(0.2, 1.0, length)))
    net = SpikingNetwork(name="s", n_steps=length, populations=[
        Population(id="a", shape={"r": rows, "bit": 6, "part": 4}, source=True)],
        encoders=[Encoder(port="x", population="a", code=code, split="re_im_signed",
                          saturate=True)])
    x = _values(rng, (rows, length), 1.0, code.bound() if over else 1.0)
    if strided:  # the same values in Fortran order (a host op's strided output)
        x = np.asfortranarray(x)
    generic = dict(TRAINS, stream=lambda c, v, n: TRAINS["stream"](c, v, n))  # the parts path
    fast_clipped, slow_clipped = {}, {}
    import backends.reference.encoding as encoding
    splits = []
    split = encoding.split_values
    encoding.split_values = lambda *a: splits.append(1) or split(*a)
    try:
        fast, _, _ = encode_inputs(net, {"x": x}, clipped=fast_clipped)
    finally:
        encoding.split_values = split
    over_bound = np.abs(np.ascontiguousarray(x).view(np.float64)).max() > code.bound()
    assert bool(splits) == over_bound  # the parts path only for values over the bound
    slow, _, _ = encode_inputs(net, {"x": x}, generic, clipped=slow_clipped)
    np.testing.assert_array_equal(fast["a"].stream.levels, slow["a"].stream.levels)
    assert fast["a"].stream.start == slow["a"].stream.start and fast_clipped == slow_clipped
