"""``split_values`` on every numeric dtype equals the plain formula (float64 parts, bit for bit)."""

from __future__ import annotations

import numpy as np
import pytest

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
