"""``Linear.evaluate`` keeps its matrix as an array per op: every call equals the product
with the matrix built from the op's tuples (real and complex matrices, many ops)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ir.ops.linear import Linear
from ir.types import TensorType


@settings(max_examples=40, deadline=None)
@given(n_in=st.integers(1, 5), n_out=st.integers(1, 5), complex_=st.booleans(),
       seed=st.integers(0, 2 ** 16))
def test_linear_evaluate_is_the_plain_product(n_in, n_out, complex_, seed):
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(n_out, n_in))
    mi = rng.normal(size=(n_out, n_in)) if complex_ else None
    op = Linear(axis="c", matrix=m.tolist(), matrix_imag=None if mi is None else mi.tolist())
    t = TensorType(axes={"a": 3, "c": n_in})
    x = rng.normal(size=(3, n_in)) + 1j * rng.normal(size=(3, n_in))
    w = m if mi is None else m + 1j * mi
    want = np.moveaxis(np.tensordot(w, x, axes=([1], [1])), 0, 1)
    for _ in range(2):  # built, then kept
        got = op.evaluate("n", [x], [t])
        assert got.tobytes() == want.tobytes()
    other = Linear(axis="c", matrix=(-m).tolist())  # another op: its own matrix
    np.testing.assert_array_equal(other.evaluate("n", [x], [t]),
                                  np.moveaxis(np.tensordot(-m, x, axes=([1], [1])), 0, 1))
