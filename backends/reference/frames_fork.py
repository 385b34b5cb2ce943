"""A frames axis on worker processes: forked children write their frames into shared rows.

``RunOptions(parallel="processes")``: the frames of a program run
(:mod:`backends.reference.frames_run`) spend part of their time in Python and in numpy
calls that keep the interpreter lock, which threads cannot run side by side and processes
can; processes pay for the fork and for the copy-on-write faults of their first writes
instead.  Where the operating system can ``fork`` (Linux), the parent
runs frame 0 itself — which builds the plans (:mod:`backends.reference.plan_cache`) and
allocates every stacked array in anonymous shared memory (:func:`shared_empty`) — then
forks ``workers`` children that inherit both, each running every ``workers``-th of the
other frames and writing its values into their rows.  Only a small record per frame
(spike counts and the like) goes back through a pipe; no array is pickled.

A frame a child did not report done — it raised, or the child died — is run again by the
parent, in frame order after the children have ended: the first frame that fails raises
its own error there, exactly as a run on one thread would.

Examples
--------
>>> import numpy as np
>>> a = shared_empty((2, 3), np.float64)
>>> a[:] = 1.0
>>> a.sum(), a.dtype
(np.float64(6.0), dtype('float64'))
>>> seen = {}
>>> def run(i):
...     a[i % 2] = i
>>> map_frames_forked(run, 2, 2, collect=lambda i: i * 10,
...                   apply=lambda i, payload: seen.__setitem__(i, payload))
>>> a[:, 0].tolist(), seen
([0.0, 1.0], {1: 10})
"""

from __future__ import annotations

import mmap
import multiprocessing
import os
from collections.abc import Callable
from math import prod
from multiprocessing.connection import wait

import numpy as np

__all__ = ["fork_available", "map_frames_forked", "private_empty", "shared_empty"]


def fork_available() -> bool:
    """Whether worker processes can be forked here (they inherit the plans and buffers)."""
    return hasattr(os, "fork") and "fork" in multiprocessing.get_all_start_methods()


def shared_empty(shape: tuple[int, ...], dtype) -> np.ndarray:
    """An uninitialised array in anonymous shared memory (forked children write into it)."""
    dtype = np.dtype(dtype)
    count = prod(shape)
    buffer = mmap.mmap(-1, max(1, count * dtype.itemsize))
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape)


def private_empty(shape: tuple[int, ...], dtype) -> np.ndarray:
    """An uninitialised array in its own anonymous private mapping (huge pages asked for).

    The stacked results of a frames axis (:class:`~backends.reference.frames_run.FrameStack`)
    are new memory, paged in once whatever allocates them; from ``malloc`` they would also
    move its adaptive thresholds, after which the frames' own temporaries were given back
    to the system and paged in anew frame after frame.  A mapping of their own leaves the
    heap as a run of single frames leaves it, and is unmapped when the array is freed.

    Examples
    --------
    >>> a = private_empty((2, 3), np.int16)
    >>> a[:] = 7
    >>> int(a.sum()), a.dtype
    (42, dtype('int16'))
    """
    dtype = np.dtype(dtype)
    count = prod(shape)
    buffer = mmap.mmap(-1, max(1, count * dtype.itemsize),
                       flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    if hasattr(mmap, "MADV_HUGEPAGE") and count * dtype.itemsize >= 4 << 20:
        buffer.madvise(mmap.MADV_HUGEPAGE)  # as numpy asks for its own large arrays
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape)


def map_frames_forked(run: Callable[[int], object], count: int, workers: int,
                      progress: Callable[[int, int], None] | None = None, *,
                      collect: Callable[[int], object], apply: Callable[[int, object], None]
                      ) -> None:
    """Call ``run(i)`` for every frame ``i < count``: frame 0 here, the others on children.

    ``collect(i)`` (in the child, after ``run(i)``) is sent to the parent, which calls
    ``apply(i, payload)``; ``progress(done, count)`` follows every frame, on the calling
    thread.  Frames the children did not report are run here afterwards, in order.
    """
    run(0)
    done = 1
    if progress is not None:
        progress(done, count)
    context = multiprocessing.get_context("fork")
    pipes, children = [], []
    for w in range(min(workers, count - 1)):
        receive, send = context.Pipe(duplex=False)
        child = context.Process(target=_child, args=(run, collect, send, range(1 + w, count,
                                                                              workers)),
                                daemon=True)
        child.start()
        send.close()
        pipes.append(receive)
        children.append(child)
    reported: set[int] = {0}
    try:
        while pipes:
            for pipe in wait(pipes):
                try:
                    index, payload = pipe.recv()
                except EOFError:
                    pipes.remove(pipe)
                    continue
                apply(index, payload)
                reported.add(index)
                done += 1
                if progress is not None:
                    progress(done, count)
    finally:
        for child in children:
            child.join()
    for index in range(count):  # what a child could not do: here, in order (errors raise)
        if index not in reported:
            run(index)
            done += 1
            if progress is not None:
                progress(done, count)


def _child(run, collect, send, frames: range) -> None:
    """A worker: run its frames, report each; stop at the first that fails (the parent
    runs it again and raises its error)."""
    try:
        for index in frames:
            run(index)
            send.send((index, collect(index)))
    except BaseException:  # noqa: BLE001 - the parent re-runs the frame and raises
        pass
    finally:
        send.close()
