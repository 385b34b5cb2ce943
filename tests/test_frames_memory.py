"""The frames axis's memory: first-spike steps in their smallest dtype, stacks in their own
mappings, the same values (bit for bit) as before and for any number of workers."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.frames_memory import private_empty
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


def _charge_all_at_once(v, first, seg, params):
    """The charging span in one block, out of place (the oracle: elementwise arithmetic, so
    blocks and writing in place must not change a bit; the closed-vs-step tests check the
    arithmetic itself)."""
    import backends.reference.spans as spans

    saved = spans.CHARGE_BLOCK
    try:
        spans.CHARGE_BLOCK = max(1, v.size)
        return spans.charge(v, first, seg, params, in_place=False)[1]
    finally:
        spans.CHARGE_BLOCK = saved


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), size=st.integers(1, 700), block=st.integers(1, 300),
       integer=st.booleans(), scaled=st.booleans(), bias=st.integers(-3, 9),
       v_th=st.integers(1, 400), start=st.integers(0, 20), length=st.integers(1, 60),
       in_place=st.booleans(), spiking=st.booleans())
def test_charge_in_blocks_gives_the_bits_of_all_at_once(seed, size, block, integer, scaled,
                                                        bias, v_th, start, length, in_place,
                                                        spiking):
    import backends.reference.spans as spans
    from backends.reference.neuron import PhaseSpan, StepParams
    from compiler.snn import NeuronParams, Phase

    rng = np.random.default_rng(seed)
    n_steps = start + length
    reps = 2 if scaled else 1
    params = StepParams.from_params(
        NeuronParams(du=1.0, dv=0.0, v_th=float(v_th), reset="fire_once",
                     phases=(Phase(start_step=0, bias=float(bias), input_on=False),),
                     **({"scale_axis": "r", "scales": (1.0, 3.0)} if scaled else {})),
        n_steps, integer=integer, shape={"r": 2} if scaled else None)
    size = size + size % reps
    seg = PhaseSpan(start, n_steps, int(bias) if integer else float(bias), False, spiking)
    v = (rng.integers(-50, 500, size) if integer else rng.normal(100.0, 150.0, size))
    first = np.where(rng.random(size) < 0.3, rng.integers(0, max(1, start), size), -1)
    want_first = first.copy()
    want_end = (_charge_all_at_once(v.copy(), want_first, seg, params)
                if bias != 0 or spiking else v)
    saved, given = spans.CHARGE_BLOCK, v.copy()
    try:
        spans.CHARGE_BLOCK = block
        u, end = spans.charge(given, first, seg, params, in_place=in_place)
    finally:
        spans.CHARGE_BLOCK = saved
    assert end.dtype == want_end.dtype and end.tobytes() == want_end.tobytes()
    assert (end is given) == (in_place or (bias == 0 and not spiking))
    if not in_place:  # the caller's start values are kept
        assert given.tobytes() == v.tobytes()
    assert first.tolist() == want_first.tolist() and not u.any()


@settings(max_examples=40, deadline=None)
@given(count=st.integers(0, 12), workers=st.integers(1, 4),
       failing=st.sets(st.integers(0, 11), max_size=3))
def test_map_frames_runs_each_frame_once_and_raises_the_earliest_failure(count, workers,
                                                                         failing):
    import threading

    from backends.reference.frames_run import map_frames

    ran, seen, caller = [], [], threading.get_ident()
    lock = threading.Lock()

    def run(i):
        with lock:
            ran.append(i)
        if i in failing:
            raise ValueError(f"frame {i}")

    def progress(done, total):
        assert threading.get_ident() == caller  # always on the calling thread
        seen.append((done, total))

    bad = sorted(failing & set(range(count)))
    try:
        map_frames(run, count, workers, progress)
    except ValueError as err:
        assert bad and str(err) == f"frame {min(set(ran) & set(bad))}"
        assert bad[0] in ran  # frames start in order: the first failure always ran
    else:
        assert not bad
    assert len(ran) == len(set(ran))  # no frame twice
    if not bad:
        assert sorted(ran) == list(range(count))
        assert seen == [(i + 1, count) for i in range(count)]


@given(st.lists(st.lists(st.sampled_from([0.0, -0.0, 1.5, -2.0, 3e300, -3e300, 1e-310,
                                          np.inf, -np.inf]) | st.floats(allow_nan=False),
                         min_size=3, max_size=3), min_size=1, max_size=4))
def test_a_silent_span_sums_its_currents_as_zeros_plus_each(currents):
    from backends.reference.spans import _accumulate

    arrays = [np.array(c, np.float64) for c in currents]
    with np.errstate(all="ignore"):  # inf - inf: the same NaN either way
        want = np.zeros(3)
        for a in arrays:
            want += a
        got = None
        for a in arrays:
            got = _accumulate(got, a.copy(), (3,), np.float64)
    assert got.tobytes() == want.tobytes()


def test_a_progress_callback_that_raises_stops_the_frames_not_started():
    import threading
    import time

    import pytest

    from backends.reference.frames_run import map_frames

    ran, caller, gate = [], threading.current_thread(), threading.Event()

    def run(i):
        ran.append(i)
        if threading.current_thread() is not caller:  # a helper: busy until progress raised
            gate.wait()
            time.sleep(0.01)

    def progress(done, total):
        gate.set()
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        map_frames(run, 50, 2, progress)
    assert len(ran) <= 3 and len(ran) == len(set(ran))  # the helper stopped taking frames


def test_lazy_arrays_reach_a_worker_process_as_a_plain_dict():
    """A forked worker sends its light results through a pipe (pickled): a lazy mapping
    goes as the dict of its arrays, every lazy value computed."""
    import pickle

    from backends.reference.result import LazyArrays

    lazy = LazyArrays({"a": np.arange(3), "b": lambda: np.ones(2, np.int16)})
    back = pickle.loads(pickle.dumps(lazy))
    assert type(back) is dict and sorted(back) == ["a", "b"]
    assert back["a"].tolist() == [0, 1, 2] and back["b"].dtype == np.int16


def test_a_freed_stack_lends_its_mapping_to_the_next_while_freed_memory_is_held(monkeypatch):
    import gc

    from backends.reference import frames_memory

    freed = frames_memory._Freed(3 * 8000)
    monkeypatch.setattr(frames_memory, "_FREED", freed)
    monkeypatch.setattr(frames_memory, "held", lambda: (1, 1))
    a = private_empty((1000,), np.float64)
    address = a.ctypes.data
    b = private_empty((1000,), np.float64)  # a is alive: a mapping of its own
    assert b.ctypes.data != address
    view = a[10:]
    del a
    gc.collect()
    assert private_empty((1000,), np.float64).ctypes.data != address  # a view keeps it
    del view
    gc.collect()
    c = private_empty((1000,), np.float64)
    assert c.ctypes.data == address  # a's mapping, kept for the next stack of its size
    assert private_empty((999,), np.float64).ctypes.data != b.ctypes.data
    monkeypatch.setattr(frames_memory, "held", lambda: None)
    d = private_empty((1000,), np.float64)  # made while nothing is held: never kept
    kept = freed._bytes
    del d
    gc.collect()
    assert freed._bytes == kept


def test_kept_stacks_never_exceed_their_limit(monkeypatch):
    import gc

    from backends.reference import frames_memory

    freed = frames_memory._Freed(2 * 8000)
    monkeypatch.setattr(frames_memory, "_FREED", freed)
    monkeypatch.setattr(frames_memory, "held", lambda: (1, 1))
    stacks = [private_empty((1000,), np.float64) for _ in range(5)]
    del stacks
    gc.collect()
    assert freed._bytes == 2 * 8000 and sum(len(v) for v in freed._kept.values()) == 2
