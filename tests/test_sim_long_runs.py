"""Long runs of addends summed in numpy's own pairwise order, bit for bit as
``np.add.reduceat`` (the step engine's and the direct delivery's arithmetic)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.row_sums import PAIRWISE_BLOCK, grouped_sums, long_run_sums


@settings(max_examples=150, deadline=None)
@given(lengths=st.lists(st.integers(9, PAIRWISE_BLOCK + 40), min_size=1, max_size=6),
       integer=st.booleans(), zeros=st.booleans(), seed=st.integers(0, 2 ** 16))
def test_long_runs_equal_reduceat(lengths, integer, zeros, seed):
    rng = np.random.default_rng(seed)
    total = sum(lengths) + 5
    if integer:
        rows = rng.integers(-2 ** 40, 2 ** 40, (total, 7))
    else:  # magnitudes far apart, so every reordering of a sum would show
        rows = rng.standard_normal((total, 7)) * 10.0 ** rng.integers(-8, 9, (total, 1))
        if zeros:
            rows[rng.random(rows.shape) < 0.3] = -0.0
    order = rng.permutation(len(lengths))
    first = (np.cumsum(lengths) - lengths + 2)[order]
    length = np.array(lengths)[order]
    want = np.stack([np.add.reduceat(rows[f:f + n], [0], axis=0)[0]
                     for f, n in zip(first, length, strict=True)])
    got = long_run_sums(lambda at: rows[at], first, length)
    assert got.dtype == want.dtype and got.tobytes() == want.tobytes()


@settings(max_examples=60, deadline=None)
@given(counts=st.lists(st.integers(1, 40), min_size=1, max_size=12), scaled=st.booleans(),
       seed=st.integers(0, 2 ** 16))
def test_grouped_sums_with_long_runs_equal_reduceat(counts, scaled, seed):
    rng = np.random.default_rng(seed)
    table = rng.standard_normal((30, 5)) * 10.0 ** rng.integers(-6, 7, (30, 1))
    rows = np.repeat(np.arange(len(counts)) * 3, counts)
    index = rng.integers(0, 30, rows.size)
    scale = rng.integers(1, 9, rows.size).astype(np.float64) if scaled else None
    hit, sums = grouped_sums(table, index, rows, scale)
    addends = table[index] * (scale[:, None] if scaled else 1.0)
    starts = np.cumsum(counts) - counts
    want = np.add.reduceat(addends, starts, axis=0)
    assert hit.tolist() == (np.arange(len(counts)) * 3).tolist()
    assert sums.tobytes() == want.tobytes()
