"""The step engine's half-width gathers: weights whose columns pair as ``(y, −y)``.

A two-ReLU output puts ``y`` and ``−y`` on the two parts of its neurons, so the
odd columns of ``W`` are the even ones negated.  :class:`TrainCurrents` with
``paired=True`` then gathers and sums the even halves only and
``MatrixDelivery.add_paired_rows`` adds them and subtracts them.  The claim
checked here: the target ends with the same bits as with the full rows, step
after step, for floats over 600 orders of magnitude with ±0 and subnormals, runs
longer than numpy's pairwise block, several frames and permuted target axes.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.delivery import TrainCurrents
from backends.reference.matrix import MatrixDelivery
from compiler.snn import MatrixProjection, Population


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.int64)


def _nasty(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    x = rng.normal(size=shape) * 10.0 ** rng.integers(-320, 300, size=shape)
    x[rng.random(shape) < 0.1] = 0.0
    x[rng.random(shape) < 0.1] = -0.0
    return x


def _paired(half: np.ndarray) -> np.ndarray:
    """``(h_0, −h_0, h_1, −h_1, …)`` column pairs."""
    return np.stack([half, -half], axis=-1).reshape(half.shape[0], -1)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), permuted=st.booleans(),
       block_bytes=st.sampled_from([1, 4096, 1 << 20]))
def test_paired_halves_add_the_same_bits_as_full_rows(seed: int, permuted: bool,
                                                      block_bytes: int) -> None:
    rng = np.random.default_rng(seed)
    n_in, n_pairs, n_reps = int(rng.integers(1, 41)), int(rng.integers(1, 5)), 2
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=_paired(_nasty(rng, (n_in, n_pairs))))
    src = Population(id="a", shape={"r": n_reps, "i": n_in}, source=True)
    tgt_shape = {"o": 2 * n_pairs, "r": n_reps} if permuted else {"r": n_reps, "o": 2 * n_pairs}
    dl = MatrixDelivery.build(proj, src, Population(id="b", shape=tgt_shape))
    assert dl.paired_halves[0] is not None
    assert (dl.target_index is not None) == permuted
    n_frames, n_steps = int(rng.integers(1, 3)), int(rng.integers(1, 5))
    steps = rng.integers(0, n_steps + 1, size=n_frames * src.size)  # n_steps: never spikes
    flat = np.flatnonzero(steps < n_steps)
    order = np.argsort(steps[flat], kind="stable")
    flat, spike_steps = flat[order], steps[flat][order]
    full = TrainCurrents(dl, 0, 0, flat, spike_steps, n_frames, n_steps, block_bytes)
    half = TrainCurrents(dl, 0, 0, flat, spike_steps, n_frames, n_steps, block_bytes,
                         paired=True)
    assert half.table.shape == (n_in, n_pairs)
    ref, got = np.zeros(n_frames * 2 * n_pairs * n_reps), np.zeros(n_frames * 2 * n_pairs * n_reps)
    with np.errstate(all="ignore"):
        for t in range(n_steps):
            a, b = full.at(t), half.at(t)
            assert (a is None) == (b is None)
            if a is None:
                continue
            np.testing.assert_array_equal(a[0], b[0])
            full.add_rows(*a, ref)
            half.add_rows(*b, got)
            np.testing.assert_array_equal(_bits(got), _bits(ref))


def test_unpaired_weights_have_no_half() -> None:
    w = np.array([[1.0, -1.0, 2.0, -2.5]])
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=w)
    dl = MatrixDelivery.build(proj, Population(id="a", shape={"i": 1}, source=True),
                              Population(id="b", shape={"o": 4}))
    assert dl.paired_halves == (None,)
    tc = TrainCurrents(dl, 0, 0, np.array([0]), np.array([0]), 1, 1, paired=True)
    assert tc.table is dl.weights[0] and tc.add_rows == dl.add_rows
