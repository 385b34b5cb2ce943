"""Worker processes forked for one program, each with two slots of shared memory.

:class:`FramePool` is the mechanism of :mod:`backends.reference.frames_pool` (which keeps one
for the program last run on processes and says when to fork a new one).  Each worker has
:data:`SLOTS` slots (:mod:`backends.reference.frames_memory`), so it runs one frame while
the parent hands out the next: the parent writes a frame's inputs into a free slot and sends
their header.  The worker runs the frame and, when the pool knows the arrays a frame gives
(:attr:`FramePool.layout`) and :meth:`FramePool.rows` made shared stacks for them
(:mod:`backends.reference.frames_rows`), writes them straight into its row of each and sends
back only the result's light record; otherwise it packs them into the same slot after the
inputs and sends their header.  A result that does not fit is reported with the bytes it
needs; one that holds Python objects comes through the pipe; a frame that raises is reported
failed (the parent runs it again and raises its error).  A worker ignores ``SIGINT``: the
parent handles Ctrl-C and ends the pool.  The workers end when the pool is closed or its
program is freed.

When there are at least as many cores as workers (those the process may run on,
``os.sched_getaffinity``), each worker is bound to a core of its own (:func:`worker_cores`).
The parent wakes the workers through their pipes, and the kernel tends to run a task it
wakes on the waking task's core; unbound, two workers woken together start on one core and
wait to be moved apart.  The gain is small: a frames axis of the carrada preset on two
workers ran 1.75 to 1.84 times as fast as on one (median 1.77, eight runs of seven pairs of
calls) bound, and 1.68 to 1.83 times (median 1.74) unbound, on a quiet 2-core machine.  With
more workers than cores they are left to the scheduler.

Examples
--------
>>> import numpy as np
>>> from backends.reference.program import ProgramResult
>>> class Toy:
...     pass
>>> def run_one(inputs, options):
...     return ProgramResult(values={"y": 2 * inputs["x"]}, outputs={})
>>> toy, got = Toy(), {}
>>> pool = FramePool(toy, (), run_one, workers=2, slot_bytes=1 << 16)
>>> pool.map([0, 1, 2], lambda i: {"x": np.full(3, i)}, None,
...          lambda i, r: got.__setitem__(i, r.values["y"].tolist()), lambda: None)
([], [], 0)
>>> pool.layout                     # learned from the frames: the next call writes rows
[((3,), dtype('int64'))]
>>> pool.close()
>>> sorted(got.items())
[(0, [0, 0, 0]), (1, [2, 2, 2]), (2, [4, 4, 4])]
"""

from __future__ import annotations

import contextlib
import mmap
import multiprocessing
import os
import signal
import weakref
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from multiprocessing.connection import wait
from multiprocessing.reduction import recv_handle, send_handle

import numpy as np

from backends.reference.frames_memory import (
    pack_arrays,
    restore_result,
    shared_empty,
    strip_result,
    unpack_arrays,
)
from backends.reference.frames_rows import Layout, Rows, RowStacks

__all__ = ["SLOTS", "FramePool", "worker_cores"]

#: Slots per worker: one frame runs while the parent copies the previous one out.
SLOTS = 2


def worker_cores(workers: int) -> list[int | None]:
    """The core each of ``workers`` workers is bound to (None: not bound; module docstring).

    Examples
    --------
    >>> cores = worker_cores(1)
    >>> len(cores) == 1 and (cores[0] is None or isinstance(cores[0], int))
    True
    >>> worker_cores(10_000) == [None] * 10_000   # more workers than cores: none bound
    True
    """
    if not hasattr(os, "sched_getaffinity") or not hasattr(os, "sched_setaffinity"):
        return [None] * workers
    cores = sorted(os.sched_getaffinity(0))
    if workers > len(cores):
        return [None] * workers
    return cores[:workers]


class FramePool:
    """Worker processes forked for one program, each with :data:`SLOTS` shared slots.

    Parameters
    ----------
    program : object
        The program the workers run (held weakly: the pool ends when it is freed).
    key : tuple
        What the workers were forked with (kept as :attr:`key`:
        :func:`~backends.reference.frames_pool.pool_key`).
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
        #: The arrays a frame gives (shapes, dtypes), from the last frame seen; None: unknown.
        self.layout: Layout | None = None
        self.row_stacks = RowStacks()
        self._program = weakref.ref(program)
        self.slots = [[shared_empty((slot_bytes,), np.uint8) for _ in range(SLOTS)]
                      for _ in range(workers)]
        context = multiprocessing.get_context("fork")
        self.conns, self.children = [], []
        #: The core each worker is bound to (None: not bound).
        self.cores = worker_cores(workers)
        for w in range(workers):
            here, there = context.Pipe(duplex=True)
            child = context.Process(target=_serve, name=f"radarsnn-frames-{w}", daemon=True,
                                    args=(there, [*self.conns, here], run_one, self.slots[w],
                                          self.cores[w]))
            child.start()
            there.close()
            self.conns.append(here)
            self.children.append(child)
        self._finalizer = weakref.finalize(program, _close, self.conns, self.children,
                                           self.owner, self.row_stacks)

    def matches(self, program, workers: int) -> bool:
        """Whether this pool, alive in this process, runs ``program`` on ``workers`` workers
        (its :attr:`key` is the caller's to compare)."""
        return (self.usable() and self._program() is program and workers == self.workers
                and all(c.is_alive() for c in self.children))

    def usable(self) -> bool:
        """Whether this pool is this process's own and was not ended."""
        return not self.broken and self.owner == os.getpid() and self._finalizer.alive

    def runs(self, program) -> bool:
        """Whether this pool is usable and was forked for ``program``."""
        return self.usable() and self._program() is program

    def close(self) -> None:
        """End the workers (each finishes the frame it runs)."""
        self.broken = True
        self._finalizer()

    def rows(self, count: int) -> Rows | None:
        """Shared stacks of ``count`` rows for :attr:`layout` (None if it is unknown or
        cannot be shared, :mod:`backends.reference.frames_rows`), sent to every worker."""
        rows = None if self.layout is None else self.row_stacks.rows(count, self.layout)
        forget = self.row_stacks.take_dropped()
        new = self.row_stacks.take_new()
        try:
            for conn, child in zip(self.conns, self.children, strict=True):
                if forget:
                    conn.send(("forget", forget))
                for block in new:
                    conn.send(("map", block.id, block.size))
                    send_handle(conn, block.fd, child.pid)
        except OSError:  # a worker is gone: the frames travel through the slots, or run here
            self.broken = True
            return None
        finally:
            for block in new:
                block.close_fd()
        return rows

    def map(self, frames: Sequence[int], inputs_of: Callable[[int], Mapping[str, np.ndarray]],
            options, store: Callable[[int, object], None], done: Callable[[], None],
            rows: Rows | None = None) -> tuple[list[int], list[int], int]:
        """Run ``frames`` on the workers; ``store(i, result)`` and ``done()`` for each done.

        With ``rows`` (:meth:`rows`), a worker writes a frame whose arrays match their
        layout straight into its row, and ``store`` gets that row's views.  Returns the
        frames not done (a worker raised or died), the frames not started and the slot
        bytes a frame needed when it did not fit (0 if every frame fitted: the frames not
        started then follow a failure, else they need a larger pool).
        """
        spec = None if rows is None else rows.spec()
        try:  # what every frame of this call shares, once per worker
            for conn in self.conns:
                conn.send(("call", options, spec))
        except OSError:
            self.broken = True
            return [], sorted(frames), 0
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
            self.conns[w].send((i, s, list(inputs), header, end))
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
                if status == "rows":
                    store(i, restore_result(light, rows.row_views(i)))
                    done()
                elif status == "slot":
                    store(i, restore_result(light, unpack_arrays(payload, self.slots[w][s])))
                    self.layout = [(shape, dtype) for _, dtype, shape in payload]
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


def _close(conns, children, owner: int, row_stacks: RowStacks) -> None:
    """End a pool's workers (only from the process that forked them)."""
    if os.getpid() != owner:
        return
    row_stacks.close()
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


def _serve(conn, inherited, run_one: Callable, slots: Sequence[np.ndarray],
           core: int | None = None) -> None:
    """A worker: run the frames it is sent until told to stop (None) or the parent ends
    (bound to ``core`` if one is given).

    Besides frames, the parent sends ``("call", options, spec)`` before a call's frames,
    ``("map", id, size)`` followed by a shared block's file descriptor, and ``("forget",
    ids)`` for blocks it let go.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if core is not None:
        with contextlib.suppress(OSError):  # a core taken away since: run where allowed
            os.sched_setaffinity(0, {core})
    for other in inherited:  # the parent's ends: the parent's exit must reach this worker
        other.close()
    blocks: dict[int, mmap.mmap] = {}
    call: tuple = (None, None)  # the options and row spec of the current call
    while True:
        try:
            message = conn.recv()
            if message is not None and message[0] == "map":
                fd = recv_handle(conn)
                blocks[message[1]] = mmap.mmap(fd, message[2])
                os.close(fd)
                continue
        except (EOFError, OSError):
            return
        if message is None:
            return
        if message[0] == "call":
            call = message[1:]
        elif message[0] == "forget":
            for block_id in message[1]:
                blocks.pop(block_id, None)
        else:
            conn.send(_run_frame(message, *call, run_one, slots, blocks))


def _run_frame(message: tuple, options, spec, run_one: Callable,
               slots: Sequence[np.ndarray], blocks: Mapping[int, mmap.mmap]) -> tuple:
    """One frame in a worker: its reply (index, slot, status, light record, payload)."""
    i, s, names, header, start = message
    slot = slots[s]
    try:
        inputs = dict(zip(names, unpack_arrays(header, slot), strict=True))
        light, arrays = strip_result(run_one(inputs, options))
        if spec is not None and len(spec) == len(arrays) and all(
                block_id in blocks and a.shape == shape[1:] and a.dtype == dtype
                for (block_id, shape, dtype), a in zip(spec, arrays, strict=True)):
            for (block_id, shape, dtype), a in zip(spec, arrays, strict=True):
                np.ndarray(shape, dtype, buffer=blocks[block_id])[i] = a
            return i, s, "rows", light, None
        packed, end = pack_arrays(arrays, slot, start)
        if packed is not None:
            return i, s, "slot", light, packed
        if any(a.dtype.hasobject for a in arrays):  # Python objects: through the pipe
            return i, s, "pipe", light, arrays
        return i, s, "big", None, end
    except Exception:  # noqa: BLE001 - the parent runs the frame again and raises
        return i, s, "failed", None, None
