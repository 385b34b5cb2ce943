"""A frames axis on worker processes, forked once and kept for the next call.

``RunOptions(parallel="processes")`` — and ``"auto"``, the default, where it is safe
(:func:`~backends.reference.frames_run.default_parallel`): a frame spends part of its time
in Python and in numpy calls that keep the interpreter lock, which threads cannot run side
by side and processes can.  Forking for every call costs more than it gains (the
children's first writes fault their pages in), so the workers are forked once, after the
parent has run a frame itself — which builds the program's plans
(:mod:`backends.reference.plan_cache`), inherited by the children — and are kept for the
following calls on the same program.

A frame's inputs travel through slots of shared memory, two per worker
(:class:`~backends.reference.frames_workers.FramePool`), and its result goes straight into
the rows of stacks in shared memory (:mod:`backends.reference.frames_rows`) once the
arrays a frame gives are known — or back through its slot when they differ: nothing large
is pickled.  The slots are sized on the first frame; a result that outgrows them makes a
new pool, forked with larger ones.

The pool is kept for one program at a time (running another program on processes, or
changing a part of this one — a segment, a network's populations, projections, encoders,
decoders or step count — forks a new one) and ends when its program is freed, at exit, or
with :func:`close_frame_workers`.  Its workers are copies of this process as it was when
they were forked: code or data changed since then outside the program's parts is not
seen; call :func:`close_frame_workers` after such a change.

A frame a worker did not report done — it raised, or the worker died — is run again by
the parent after the others, in frame order: the first frame that fails raises its own
error there, exactly as a run on one thread would.  A worker ignores ``SIGINT`` (the
parent handles Ctrl-C and ends the pool).

Examples
--------
>>> pool_key(object(), None, None)[2]     # what a pool is kept for: program, engine, plans
()
>>> _ = close_frame_workers()
>>> close_frame_workers()                 # none left: nothing to do
False
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from backends.reference.frames_memory import packed_bytes, restore_result, strip_result
from backends.reference.frames_rows import Rows
from backends.reference.frames_workers import FramePool

__all__ = ["close_frame_workers", "has_workers", "map_frames_pooled", "pool_key",
           "workers_cpu_s"]

#: Head room of a slot over the first frame's inputs and result (bytes: × 1.25 + this).
_SLOT_MARGIN = 1 << 20

_LOCK = threading.Lock()            # held by the call that uses the pool
_CURRENT: list[FramePool | None] = [None]
_PARTS = ("populations", "projections", "encoders", "decoders")


def pool_key(program, engine, plans: Sequence | None) -> tuple:
    """What a pool's workers were forked with: the program, the engine, the plans given,
    and the program's parts (compared by identity; see the module docstring)."""
    segments = tuple(getattr(program, "segments", ()))
    networks = tuple(getattr(program, "networks", ()))
    parts = tuple((n.n_steps, *(tuple(getattr(n, p)) for p in _PARTS)) for n in networks)
    evaluators = tuple(dict(getattr(program, "evaluators", {}) or {}).items())
    return (engine, tuple(plans) if plans is not None else None, segments, parts, evaluators)


def _same(a: object, b: object) -> bool:
    """Equal by identity, element by element through tuples (numbers and names by value)."""
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, int | str) and type(a) is type(b):
        return a == b
    return a is b


def slot_bytes_for(inputs: Mapping[str, np.ndarray], result) -> int:
    """Slot bytes for frames like this one: its inputs and result arrays, with head room."""
    _, arrays = strip_result(result)
    used = packed_bytes(arrays, packed_bytes([np.asarray(v) for v in inputs.values()]))
    return int(used * 1.25) + _SLOT_MARGIN


def map_frames_pooled(program, key: tuple, run_one: Callable, count: int, workers: int,
                      inputs_of: Callable[[int], Mapping[str, np.ndarray]], options,
                      store: Callable[[int, object], None],
                      progress: Callable[[int, int], None] | None = None,
                      rows_made: list[Rows] | None = None) -> bool:
    """Run frames ``0 .. count − 1`` on the pool of worker processes (module docstring).

    ``run_one(inputs, options)`` runs one frame; ``store(i, result)`` takes frame ``i``'s
    result (in the calling process, any order): views of a row of shared stacks when the
    workers wrote them there, each :class:`~backends.reference.frames_rows.Rows` of which is
    appended to ``rows_made`` first (the caller's stacks adopt them:
    :class:`~backends.reference.frames_run.FrameStack`); ``progress(done, count)`` follows
    every frame.  Returns False, having run nothing, when another thread is using the pool
    (the caller runs the frames on threads instead).
    """
    if not _LOCK.acquire(blocking=False):
        return False
    try:
        _run_pooled(program, key, run_one, count, workers, inputs_of, options, store,
                    progress, [] if rows_made is None else rows_made)
    finally:
        _LOCK.release()
    return True


def _run_pooled(program, key, run_one, count, workers, inputs_of, options, store,
                progress, rows_made) -> None:
    finished = [0]

    def done() -> None:
        finished[0] += 1
        if progress is not None:
            progress(finished[0], count)

    def here(i: int):
        result = run_one(inputs_of(i), options)
        store(i, result)
        done()
        return result

    pool = _CURRENT[0]
    todo = list(range(count))
    if pool is not None and not (pool.matches(program, workers) and _same(key, pool.key)):
        pool.close()
        pool = _CURRENT[0] = None
    first = None
    if pool is None:  # frame 0 here: it builds the plans the workers inherit
        first = run_one(inputs_of(todo.pop(0)), options)
        pool = _new_pool(program, key, run_one, workers, slot_bytes_for(inputs_of(0), first))
        light, arrays = strip_result(first)
        pool.layout = [(a.shape, a.dtype) for a in arrays]
    rows = pool.rows(count)
    if rows is not None:
        rows_made.append(rows)
    if first is not None:  # into its rows too, so the stacks are the shared ones
        if rows is not None:
            for stack, array in zip(rows.arrays, arrays, strict=True):
                stack[0] = array
            first = restore_result(light, rows.row_views(0))
        store(0, first)
        done()
    lost: list[int] = []
    try:
        while todo:
            failed, todo, need = pool.map(todo, inputs_of, options, store, done, rows)
            lost += failed
            if not need:
                break
            pool.close()  # a frame outgrew the slots: fork a pool with larger ones
            pool = _new_pool(program, key, run_one, workers,
                             max(int(need * 1.25) + _SLOT_MARGIN, 2 * pool.slot_bytes))
    except BaseException:
        pool.close()  # frames may still be running: this pool's state is unknown
        _CURRENT[0] = None
        raise
    if pool.broken:
        pool.close()
        _CURRENT[0] = None
    for i in sorted(lost + todo):  # what the workers did not do: here, in order (errors raise)
        here(i)


def _new_pool(program, key, run_one, workers, slot_bytes) -> FramePool:
    pool = _CURRENT[0] = FramePool(program, key, run_one, workers, slot_bytes)
    return pool


def _after_fork_in_child() -> None:
    """A forked process starts with no pool of its own (its parent's is not its to use)."""
    global _LOCK
    _LOCK = threading.Lock()
    _CURRENT[0] = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork_in_child)


def workers_cpu_s() -> tuple[float, float]:
    """User and system CPU seconds the live worker processes have used so far (read from
    ``/proc``; (0, 0) where there is none).  Workers that have ended are in
    ``resource.getrusage(resource.RUSAGE_CHILDREN)``.

    Examples
    --------
    >>> user, system = workers_cpu_s()
    >>> user >= 0 and system >= 0
    True
    """
    pool = _CURRENT[0]
    if pool is None or pool.owner != os.getpid():
        return 0.0, 0.0
    ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    user = system = 0.0
    for child in pool.children:
        try:
            with open(f"/proc/{child.pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        user += int(fields[11]) / ticks  # utime, stime: fields 14 and 15 of proc(5)
        system += int(fields[12]) / ticks
    return user, system


def has_workers(program) -> bool:
    """Whether worker processes are kept for ``program`` (forked by an earlier run)."""
    pool = _CURRENT[0]
    return pool is not None and pool.runs(program)


def close_frame_workers() -> bool:
    """End the worker processes kept for frames axes (:mod:`backends.reference.frames_pool`).

    The next run on processes forks new ones.  Call it after changing code or data the
    workers use outside the program's own parts, or to give their memory back.  Returns
    whether there were workers to end.
    """
    with _LOCK:
        pool, _CURRENT[0] = _CURRENT[0], None
        if pool is None or pool.owner != os.getpid():
            return False
        pool.close()
        return True
