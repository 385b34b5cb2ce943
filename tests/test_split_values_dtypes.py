"""``split_values`` on every numeric dtype equals the plain formula (float64 parts, bit for bit)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from compiler.snn.parts import split_values


def _plain(x, split):
    re, im = np.real(x).astype(np.float64), np.imag(x).astype(np.float64)
    parts = {"re_im": (re, im), "signed": (np.maximum(re, 0.0), np.maximum(-re, 0.0)),
             "re_im_signed": (np.maximum(re, 0), np.maximum(-re, 0), np.maximum(im, 0),
                              np.maximum(-im, 0))}[split]
    return np.stack(parts, axis=-1)


VALUES = [np.array([True, False]), np.array([3, -2, 0], np.int8), np.array([7, 0], np.uint16),
          np.array([1.5, -0.0], np.float16), np.array([2.0, -1.0], ">f8"),
          np.array([1 - 2j, -0.0 + 0j], np.complex64), np.arange(6).reshape(2, 3).T,
          np.zeros((0, 2))]


@pytest.mark.parametrize("split", ["re_im", "signed", "re_im_signed"])
@pytest.mark.parametrize("x", VALUES, ids=lambda x: str(x.dtype))
def test_split_values_equals_the_plain_formula(x, split):
    got, want = split_values(x, split), _plain(x, split)
    assert got.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()


_SPECIAL = [0.0, -0.0, 1.5, -2.25, 5e-324, -5e-324, np.inf, -np.inf, np.nan, 1e308]


@settings(max_examples=60, deadline=None)
@given(shape=st.lists(st.integers(0, 5), min_size=0, max_size=3), seed=st.integers(0, 2 ** 16),
       strided=st.booleans())
def test_complex128_pairs_path_equals_the_plain_formula(shape, seed, strided):
    """The complex128 fast path (re, im pairs in one call per operation) and, on strided
    views, the per-component path: the plain formula bit for bit, signed zeros and NaN too."""
    rng = np.random.default_rng(seed)
    size = int(np.prod(shape)) * (2 if strided else 1)
    re, im = (np.where(rng.random(size) < 0.3, rng.choice(_SPECIAL, size), rng.normal(0, 9, size))
              for _ in range(2))
    x = np.empty(size, np.complex128)
    x.real, x.imag = re, im  # signed zeros and non-finite parts kept as drawn
    x = x[::2] if strided else x
    x = x.reshape(shape)
    with np.errstate(invalid="ignore"):
        got, want = split_values(x, "re_im_signed"), _plain(x, "re_im_signed")
    assert got.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()
