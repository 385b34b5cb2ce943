"""Worker processes kept between calls (:mod:`backends.reference.frames_pool`).

* the frames of a program run on the pool give the bits of one thread, call after call, on
  the same worker processes; a changed part of the program, another program or another
  number of workers forks new ones;
* a result too large for the slots, arrays of Python objects, a worker that dies and a
  frame that raises all give the frames' own results or errors, in frame order;
* the pool ends with its program, with :func:`close_frame_workers`, and after Ctrl-C;
* ``auto`` takes processes only where forking is safe.
"""

from __future__ import annotations

import gc
import os
import threading

import numpy as np
import pytest

from backends.reference import RunOptions, run_program
from backends.reference.frames_memory import fork_available
from backends.reference.frames_pool import (
    _CURRENT,
    close_frame_workers,
    has_workers,
    map_frames_pooled,
    pool_key,
    workers_cpu_s,
)
from backends.reference.frames_run import resolve_parallel
from backends.reference.program import ProgramResult
from compiler.compile import compile_graph
from tests.test_run_program_speed import _frames, _rd_chain, _same_run, _same_sims

pytestmark = pytest.mark.skipif(not fork_available(), reason="worker processes need fork "
                                 "(elsewhere frames run on threads, tested with them)")
ON_PROCESSES = RunOptions(out_of_range="clip", workers=2, parallel="processes")


@pytest.fixture
def program():
    yield compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(0, 3)})
    close_frame_workers()


def _pids() -> list[int]:
    pool = _CURRENT[0]
    return [] if pool is None else [c.pid for c in pool.children]


def _check(program, x: np.ndarray) -> None:
    got = run_program(program, {"adc": x}, options=ON_PROCESSES)
    one = run_program(program, {"adc": x}, out_of_range="clip", workers=1)
    _same_run(got, one)
    _same_sims(got.simulations, one.simulations)


def test_calls_reuse_the_workers_and_give_the_bits_of_one_thread(program):
    _check(program, _frames(1, 5))
    pids = _pids()
    assert len(pids) == 2 and has_workers(program)
    for seed, n in ((2, 6), (3, 2), (4, 9)):
        _check(program, _frames(seed, n))
        assert _pids() == pids  # the same processes: forked once


def test_a_changed_part_another_program_or_workers_fork_new_workers(program):
    _check(program, _frames(1, 4))
    first = _pids()
    program.networks[0].n_steps += 4  # a changed part: the workers' copy is stale
    _check(program, _frames(2, 4))
    second = _pids()
    assert set(second).isdisjoint(first)
    run_program(program, {"adc": _frames(2, 4)}, options=RunOptions(
        out_of_range="clip", workers=3, parallel="processes"))
    assert len(_pids()) == 3
    other = compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(5, 3)})
    _check(other, _frames(3, 4))
    assert not has_workers(program) and has_workers(other)


def test_the_pool_ends_with_its_program_and_when_closed(program):
    run_program(program, {"adc": _frames(1, 3)}, options=ON_PROCESSES)
    children = list(_CURRENT[0].children)
    assert close_frame_workers() and not close_frame_workers()
    assert not any(c.is_alive() for c in children)
    other = compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(5, 3)})
    run_program(other, {"adc": _frames(1, 3)}, options=ON_PROCESSES)
    children = list(_CURRENT[0].children)
    del other
    gc.collect()
    for c in children:
        c.join(timeout=5)
    assert not any(c.is_alive() for c in children)


def test_workers_cpu_time_is_counted(program):
    x = _frames(1, 8)
    run_program(program, {"adc": x}, options=ON_PROCESSES)
    before = sum(workers_cpu_s())
    for _ in range(20):
        run_program(program, {"adc": x}, options=ON_PROCESSES)
    assert sum(workers_cpu_s()) > before


@pytest.mark.skipif(not hasattr(os, "sched_getaffinity")
                    or len(os.sched_getaffinity(0)) < 2, reason="needs two cores to bind")
def test_workers_are_bound_to_cores_of_their_own(program):
    from backends.reference.frames_workers import worker_cores

    _check(program, _frames(3, 4))
    allowed = sorted(os.sched_getaffinity(0))
    bound = [os.sched_getaffinity(pid) for pid in _pids()]
    assert bound == [{allowed[0]}, {allowed[1]}] and _CURRENT[0].cores == allowed[:2]
    assert worker_cores(len(allowed) + 1) == [None] * (len(allowed) + 1)


def test_ctrl_c_in_progress_ends_the_pool_and_the_next_call_works(program):
    def interrupt(done, total):
        if done == 2:
            raise KeyboardInterrupt

    run_program(program, {"adc": _frames(1, 3)}, options=ON_PROCESSES)
    children = list(_CURRENT[0].children)
    with pytest.raises(KeyboardInterrupt):
        run_program(program, {"adc": _frames(1, 6)}, options=ON_PROCESSES, progress=interrupt)
    assert _CURRENT[0] is None and not any(c.is_alive() for c in children)
    _check(program, _frames(2, 5))


def test_a_dead_worker_frames_run_here(program):
    run_program(program, {"adc": _frames(1, 3)}, options=ON_PROCESSES)
    pool = _CURRENT[0]
    pool.children[0].kill()
    pool.children[0].join()
    _check(program, _frames(2, 5))  # a new pool: the old one has a dead worker
    assert pool.children[0].pid not in _pids()


# -- the pool on its own: toy frames whose results outgrow slots, hold objects, or fail


class Toy:
    """A program stand-in: the pool needs only an object to key and hold weakly."""


def _toy_run(sizes: dict[int, int], fail: set[int] = frozenset(), die: set[int] = frozenset(),
             objects: bool = False):
    def run_one(inputs, options):
        i = int(inputs["i"][0])
        if i in die and os.getpid() != PARENT:
            os._exit(3)
        if i in fail:
            raise ValueError(f"frame {i} fails")
        x = np.full(sizes.get(i, 4), float(i))
        v = {"x": x, "i": inputs["i"]}
        if objects:
            v["o"] = np.array([f"frame {i}"], dtype=object)
        return ProgramResult(values=v, outputs={"x": x})
    return run_one


PARENT = os.getpid()


def _toy_map(run_one, count: int) -> dict[int, ProgramResult]:
    toy = Toy()
    got = {}

    def store(i, result):
        got[i] = {k: np.array(v, copy=True) for k, v in result.values.items()}
        assert result.outputs["x"] is result.values["x"]

    seen = []
    assert map_frames_pooled(toy, pool_key(toy, None, None), run_one, count, 2,
                             lambda i: {"i": np.array([i])}, None, store,
                             lambda done, total: seen.append(done))
    assert seen == list(range(1, count + 1))
    close_frame_workers()
    return got


def test_a_result_that_outgrows_the_slots_forks_larger_ones():
    sizes = {0: 4, 3: 1 << 19, 5: 1 << 21}  # 4 MiB and 16 MiB of float64: past the slots
    got = _toy_map(_toy_run(sizes), 7)
    assert sorted(got) == list(range(7))
    for i, v in got.items():
        assert v["x"].shape == (sizes.get(i, 4),) and (v["x"] == i).all()


def test_arrays_of_python_objects_come_through_the_pipe():
    got = _toy_map(_toy_run({}, objects=True), 5)
    assert [got[i]["o"].tolist() for i in range(5)] == [[f"frame {i}"] for i in range(5)]


def test_a_worker_that_dies_leaves_its_frame_to_the_parent():
    got = _toy_map(_toy_run({}, die={2, 4}), 6)
    assert sorted(got) == list(range(6))


def test_the_earliest_failing_frame_raises_here():
    with pytest.raises(ValueError, match="frame 3 fails"):
        _toy_map(_toy_run({}, fail={3, 5}), 8)
    close_frame_workers()


def test_auto_takes_processes_only_where_forking_is_safe(program):
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:  # another thread: its locks could be copied held, so threads
        assert resolve_parallel("auto", 2, program) == "threads"
        assert resolve_parallel("processes", 2, program) == "processes"
        run_program(program, {"adc": _frames(1, 3)}, options=ON_PROCESSES)
        # workers already forked for this program: they are used, nothing is forked
        assert resolve_parallel("auto", 2, program) == "processes"
        assert resolve_parallel("auto", 1, program) == "threads"
    finally:
        stop.set()
        other.join()


def _frames_in_a_daemon(conn) -> None:
    program = compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(0, 3)})
    got = run_program(program, {"adc": _frames(1, 4)}, options=ON_PROCESSES)
    conn.send((resolve_parallel("processes", 2, program), got.outputs["o"].tolist()))


def test_a_daemonic_process_runs_its_frames_on_threads():
    import multiprocessing

    context = multiprocessing.get_context("fork")
    here, there = context.Pipe()
    child = context.Process(target=_frames_in_a_daemon, args=(there,), daemon=True)
    child.start()
    kind, outputs = here.recv()
    child.join()
    one = run_program(compile_graph(_rd_chain(), target=None,
                                    calibration_inputs={"adc": _frames(0, 3)}),
                      {"adc": _frames(1, 4)}, out_of_range="clip", workers=1)
    assert kind == "threads" and outputs == one.outputs["o"].tolist()


# -- rows written straight into shared stacks (frames_rows)


def _free_block_addresses(pool) -> set[int]:
    return {np.frombuffer(b.buffer, np.uint8).ctypes.data
            for blocks in pool.row_stacks._free.values() for b in blocks}


def test_results_kept_by_the_caller_are_never_written_again(program, monkeypatch):
    from backends.reference import frames_rows

    monkeypatch.setattr(frames_rows, "held", lambda: (1, 1))  # freed stacks are reused
    x1, x2 = _frames(1, 6), _frames(2, 6)
    run_program(program, {"adc": x1}, options=ON_PROCESSES)  # forks; the layout is known
    first = run_program(program, {"adc": x1}, options=ON_PROCESSES)
    kept = {k: np.array(v, copy=True) for k, v in first.values.items()}
    view = first.values["dop"][2:]
    kept_view = view.copy()
    for _ in range(3):  # stacks freed by nobody: these calls get new blocks
        _check(program, x2)
    assert all(_bits_equal(first.values[k], kept[k]) for k in kept)
    del first
    for _ in range(3):  # the view still holds its stack: never reused
        _check(program, x2)
    assert _bits_equal(view, kept_view)


def _bits_equal(a, b) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_freed_stacks_are_reused_call_after_call(program, monkeypatch):
    from backends.reference import frames_rows

    monkeypatch.setattr(frames_rows, "held", lambda: (1, 1))
    x = _frames(3, 5)
    run_program(program, {"adc": x}, options=ON_PROCESSES)
    result = run_program(program, {"adc": x}, options=ON_PROCESSES)
    address = result.values["mag"].ctypes.data
    assert address not in _free_block_addresses(_CURRENT[0])
    del result  # its stacks are the workers' shared blocks, kept for the next call
    assert address in _free_block_addresses(_CURRENT[0])
    stacks = _CURRENT[0].row_stacks
    made = len(stacks._free) and sum(len(v) for v in stacks._free.values())
    for _ in range(4):
        _check(program, x)
    assert stacks.new == [] and sum(len(v) for v in stacks._free.values()) == made


def test_a_result_of_another_layout_comes_through_the_slots(program):
    x = _frames(4, 5)
    _check(program, x)
    rasters = replace_options(record_spikes=True)
    got = run_program(program, {"adc": x}, options=rasters)
    one = run_program(program, {"adc": x}, out_of_range="clip", workers=1, record_spikes=True)
    _same_run(got, one)
    for a, b in zip(got.simulations, one.simulations, strict=True):
        assert a.spikes.keys() == b.spikes.keys()
        assert all(_bits_equal(a.spikes[k], b.spikes[k]) for k in a.spikes)
    _check(program, x)  # and back


def replace_options(**changes) -> RunOptions:
    from dataclasses import replace

    return replace(ON_PROCESSES, **changes)


def test_without_held_memory_freed_stacks_are_let_go_here_and_in_the_workers(program,
                                                                             monkeypatch):
    from backends.reference import frames_rows

    monkeypatch.setattr(frames_rows, "held", lambda: None)
    x = _frames(5, 4)
    for _ in range(4):
        _check(program, x)
        stacks = _CURRENT[0].row_stacks
        assert stacks._free == {}  # nothing kept; the ids dropped go out with the next call
    assert stacks.dropped  # the last call's, told to the workers by the next one
    _check(program, x)
