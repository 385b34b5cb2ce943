"""A frames axis on worker processes, forked once and kept for the next call.

``RunOptions(parallel="processes")`` — and ``"auto"``, the default, where it is safe
(:func:`~backends.reference.frames_run.default_parallel`): a frame spends part of its time
in Python and in numpy calls that keep the interpreter lock, which threads cannot run side
by side and processes can.  Forking for every call costs more than it gains (the
children's first writes fault their pages in), so the workers are forked once, after the
parent has run a frame itself — which builds the program's plans
(:mod:`backends.reference.plan_cache`), inherited by the children — and are kept for the
following calls on the same program.

Each worker has two *slots* of shared memory (:mod:`backends.reference.frames_memory`),
so it runs one frame while the parent copies the previous one out.  The parent writes a
frame's inputs into a free slot and sends only a header through the pipe; the worker runs
the frame (:func:`~backends.reference.run_program`, one frame), packs its result's arrays
into the same slot after the inputs and sends back a header and the result's light record
(counts and the like).  The parent copies the arrays into the stacked result and gives the
slot the next frame.  A result that outgrows the slots makes a new pool, forked with
larger ones.  Nothing large is pickled.

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

import multiprocessing
import os
import signal
import threading
import weakref
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from multiprocessing.connection import wait

import numpy as np

from backends.reference.frames_memory import (
    pack_arrays,
    packed_bytes,
    restore_result,
    shared_empty,
    strip_result,
    unpack_arrays,
)

__all__ = ["FramePool", "close_frame_workers", "has_workers", "map_frames_pooled",
           "pool_key", "workers_cpu_s"]

#: Slots per worker: one frame runs while the parent copies the previous one out.
SLOTS = 2
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


class FramePool:
    """Worker processes forked for one program, each with :data:`SLOTS` shared slots.

    Parameters
    ----------
    program : object
        The program the workers run (held weakly: the pool ends when it is freed).
    key : tuple
        :func:`pool_key` of the program when the workers are forked.
    run_one : callable
        ``run_one(inputs, options) -> ProgramResult`` of one frame (run in the workers).
    workers : int
        Worker processes.
    slot_bytes : int
        Bytes of each slot.
    """

    def __init__(self, program, key: tuple, run_one: Callable, workers: int,
                 slot_bytes: int) -> None:
        self.key, self.workers, self.slot_bytes = key, workers, slot_bytes
        self.owner = os.getpid()
        self.broken = False
        self._program = weakref.ref(program)
        self.slots = [[shared_empty((slot_bytes,), np.uint8) for _ in range(SLOTS)]
                      for _ in range(workers)]
        context = multiprocessing.get_context("fork")
        self.conns, self.children = [], []
        for w in range(workers):
            here, there = context.Pipe(duplex=True)
            child = context.Process(target=_serve, name=f"radarsnn-frames-{w}", daemon=True,
                                    args=(there, [*self.conns, here], run_one, self.slots[w]))
            child.start()
            there.close()
            self.conns.append(here)
            self.children.append(child)
        self._finalizer = weakref.finalize(program, _close, self.conns, self.children,
                                           self.owner)

    def matches(self, program, key: tuple, workers: int) -> bool:
        """Whether this pool can run ``program`` (with ``key``) on ``workers`` workers."""
        return (not self.broken and self.owner == os.getpid() and self._finalizer.alive
                and self._program() is program and workers == self.workers
                and _same(key, self.key) and all(c.is_alive() for c in self.children))

    def close(self) -> None:
        """End the workers (each finishes the frame it runs)."""
        self.broken = True
        self._finalizer()

    def map(self, frames: Sequence[int], inputs_of: Callable[[int], Mapping[str, np.ndarray]],
            options, store: Callable[[int, object], None], done: Callable[[], None]
            ) -> tuple[list[int], list[int], int]:
        """Run ``frames`` on the workers; ``store(i, result)`` and ``done()`` for each done.

        Returns the frames not done (a worker raised or died), the frames not started
        and the slot bytes a frame needed when it did not fit (0 if every frame fitted: the
        frames not started then follow a failure, else they need a larger pool).
        """
        todo = deque(frames)
        busy: dict[tuple[int, int], int] = {}
        lost: list[int] = []
        need = 0
        stop = False

        def give(w: int, s: int) -> None:
            nonlocal need, stop
            inputs = inputs_of(todo[0])
            header, end = pack_arrays([np.asarray(v) for v in inputs.values()],
                                      self.slots[w][s])
            if header is None:  # inputs larger than a slot
                need, stop = max(need, 2 * end), True
                return
            i = todo.popleft()
            self.conns[w].send((i, s, list(inputs), header, end, options))
            busy[(w, s)] = i

        for s in range(SLOTS):
            for w in range(self.workers):
                if todo and not stop:
                    give(w, s)
        while busy:
            open_ = {self.conns[w]: w for w, _ in busy}
            for conn in wait(list(open_)):
                w = open_[conn]
                try:
                    i, s, status, light, payload = conn.recv()
                except (EOFError, OSError):  # the worker died: its frames run here
                    self.broken = stop = True
                    lost += [busy.pop(k) for k in [k for k in busy if k[0] == w]]
                    continue
                del busy[(w, s)]
                if status == "slot":
                    store(i, restore_result(light, unpack_arrays(payload, self.slots[w][s])))
                    done()
                elif status == "pipe":
                    store(i, restore_result(light, payload))
                    done()
                elif status == "big":
                    need, stop = max(need, payload), True
                    todo.appendleft(i)
                else:  # it failed: the parent raises its error; no more frames start
                    lost.append(i)
                    stop = True
                if todo and not stop:
                    give(w, s)
        if self.broken:
            lost += todo
            todo.clear()
        return sorted(lost), sorted(todo), need


def _close(conns, children, owner: int) -> None:
    """End a pool's workers (only from the process that forked them)."""
    if os.getpid() != owner:
        return
    for conn in conns:
        try:
            conn.send(None)
        except OSError:
            pass
        conn.close()
    for child in children:
        child.join(timeout=2.0)
        if child.is_alive():
            child.terminate()
            child.join()


def _serve(conn, inherited, run_one: Callable, slots: Sequence[np.ndarray]) -> None:
    """A worker: run the frames it is sent until told to stop (None) or the parent ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for other in inherited:  # the parent's ends: the parent's exit must reach this worker
        other.close()
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        i, s, names, header, start, options = message
        slot = slots[s]
        try:
            inputs = dict(zip(names, unpack_arrays(header, slot), strict=True))
            light, arrays = strip_result(run_one(inputs, options))
            packed, end = pack_arrays(arrays, slot, start)
            if packed is not None:
                reply = (i, s, "slot", light, packed)
            elif any(a.dtype.hasobject for a in arrays):  # Python objects: through the pipe
                reply = (i, s, "pipe", light, arrays)
            else:
                reply = (i, s, "big", None, end)
        except Exception:  # noqa: BLE001 - the parent runs the frame again and raises
            reply = (i, s, "failed", None, None)
        conn.send(reply)


def slot_bytes_for(inputs: Mapping[str, np.ndarray], result) -> int:
    """Slot bytes for frames like this one: its inputs and result arrays, with head room."""
    _, arrays = strip_result(result)
    used = packed_bytes(arrays, packed_bytes([np.asarray(v) for v in inputs.values()]))
    return int(used * 1.25) + _SLOT_MARGIN


def map_frames_pooled(program, key: tuple, run_one: Callable, count: int, workers: int,
                      inputs_of: Callable[[int], Mapping[str, np.ndarray]], options,
                      store: Callable[[int, object], None],
                      progress: Callable[[int, int], None] | None = None) -> bool:
    """Run frames ``0 .. count − 1`` on the pool of worker processes (module docstring).

    ``run_one(inputs, options)`` runs one frame; ``store(i, result)`` takes frame ``i``'s
    result (in the calling process, any order); ``progress(done, count)`` follows every
    frame.  Returns False, having run nothing, when another thread is using the pool (the
    caller runs the frames on threads instead).
    """
    if not _LOCK.acquire(blocking=False):
        return False
    try:
        _run_pooled(program, key, run_one, count, workers, inputs_of, options, store,
                    progress)
    finally:
        _LOCK.release()
    return True


def _run_pooled(program, key, run_one, count, workers, inputs_of, options, store,
                progress) -> None:
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
    if pool is not None and not pool.matches(program, key, workers):
        pool.close()
        pool = _CURRENT[0] = None
    if pool is None:  # frame 0 here: it builds the plans the workers inherit
        first = here(todo.pop(0))
        pool = _new_pool(program, key, run_one, workers, slot_bytes_for(inputs_of(0), first))
    lost: list[int] = []
    try:
        while todo:
            failed, todo, need = pool.map(todo, inputs_of, options, store, done)
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
    return pool is not None and not pool.broken and pool.owner == os.getpid() \
        and pool._program() is program


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
