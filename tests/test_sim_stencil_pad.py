"""The stencil delivery's padding equals ``np.pad`` applied axis after axis (wrap or fill)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.stencil import _pad


@settings(max_examples=200, deadline=None)
@given(data=st.data(), n_dims=st.integers(1, 3), seed=st.integers(0, 2 ** 16))
def test_pad_equals_np_pad_axis_after_axis(data, n_dims, seed):
    rng = np.random.default_rng(seed)
    shape = (data.draw(st.integers(1, 2)),) + tuple(
        data.draw(st.integers(1, 6)) for _ in range(n_dims))
    x = rng.integers(0, 100, shape)
    axes = tuple(sorted(data.draw(st.sets(st.integers(0, n_dims - 1), min_size=1))))
    before = np.array([data.draw(st.integers(0, 8)) for _ in axes])
    after = np.array([data.draw(st.integers(0, 8)) for _ in axes])
    wrap = tuple(data.draw(st.booleans()) for _ in axes)
    want = x
    for j, a in enumerate(axes):
        pad = [(0, 0)] * x.ndim
        pad[1 + a] = (int(before[j]), int(after[j]))
        want = (np.pad(want, pad, mode="wrap") if wrap[j]
                else np.pad(want, pad, constant_values=-5))
    np.testing.assert_array_equal(_pad(x, axes, before, after, wrap, -5), want)
