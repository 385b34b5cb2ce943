"""The frames axis's memory: first-spike steps in their smallest dtype, stacks in their own
mappings, the same values (bit for bit) as before and for any number of workers."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.frames_fork import private_empty
from backends.reference.frames_run import FrameStack
from backends.reference.result import first_step_dtype, first_steps


def test_first_step_dtype_hand_values():
    assert [first_step_dtype(n) for n in (1, 100, 127, 128, 768, 32767, 32768, 2**31)] == [
        np.int8, np.int8, np.int8, np.int16, np.int16, np.int16, np.int32, np.int64]


@given(st.integers(1, 2**40))
def test_first_step_dtype_is_the_smallest_that_holds_the_count(n_steps):
    dtype = first_step_dtype(n_steps)
    info = np.iinfo(dtype)
    assert info.min <= -1 and n_steps <= info.max
    smaller = [t for t in (np.int8, np.int16, np.int32) if np.dtype(t).itemsize < dtype.itemsize]
    assert all(n_steps > np.iinfo(t).max for t in smaller)


@settings(max_examples=50)
@given(st.integers(1, 40_000), st.integers(0, 30), st.integers(0, 2**32 - 1))
def test_first_steps_keeps_every_value(n_steps, size, seed):
    first = np.random.default_rng(seed).integers(-1, n_steps, size, dtype=np.int64)
    out = first_steps(first, n_steps, (1, size))
    assert out.dtype == first_step_dtype(n_steps) and out.shape == (1, size)
    assert np.array_equal(out.astype(np.int64).ravel(), first)


def test_private_empty_is_writable_and_typed():
    a = private_empty((3, 1 << 20), np.int16)  # large enough to ask for huge pages
    a[:] = -1
    a[1, 5] = 700
    assert a.dtype == np.int16 and a.shape == (3, 1 << 20)
    assert int(a.sum()) == 700 + 1 - 3 * (1 << 20)


def test_frame_stack_rows_take_each_frame():
    stack = FrameStack(2)
    stack.put(1, {"f": np.array([[3, -1]], np.int16)}, where="t")
    stack.put(0, {"f": np.array([[0, 5]], np.int16)}, where="t")
    out = stack.arrays()["f"]
    assert out.dtype == np.int16 and out.tolist() == [[[0, 5]], [[3, -1]]]
