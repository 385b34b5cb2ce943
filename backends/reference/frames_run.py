"""A program over a leading frames axis: each frame run alone, on one or more threads.

:func:`~backends.reference.program.run_program` hands a framed run here.  Every frame
runs exactly as it would alone (so the result equals the frames run one by one, bit for
bit, whatever the number of workers), and its values are copied straight into one
``(F, *shape)`` array per node, allocated when the first frame is done: no per-frame
result is kept until the end and then stacked, so the frames' temporaries are freed and
reused frame after frame instead of paged in anew.  The stacked arrays have a memory
mapping of their own (:func:`~backends.reference.frames_memory.private_empty`), outside
``malloc``'s heap, so they do not change how it recycles the frames' temporaries.

With ``workers > 1`` the frames are shared out to that many threads (each takes the
next frame not yet started).  numpy and BLAS release the interpreter lock in their
large operations, which is where a frame's time goes; threads share the program's plans
(:mod:`backends.reference.plan_cache`), so nothing is copied or sent anywhere.

Examples
--------
>>> import numpy as np
>>> stack = FrameStack(3)
>>> for i in (2, 0, 1):                    # frames may finish in any order
...     stack.put(i, {"y": np.full(2, float(i))}, where="run")
>>> stack.arrays()["y"].tolist()
[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]
>>> resolve_workers(None, 8) >= 1, resolve_workers(4, 2)
(True, 2)
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import TypeVar

import numpy as np

from backends.reference.frames_memory import fork_available, private_empty
from backends.reference.frames_pool import has_workers
from backends.reference.frames_rows import is_row
from backends.reference.result import SimResult
from backends.reference.run_options import RunOptions
from ir.errors import SimulationError

__all__ = ["FrameStack", "SimStack", "available_cores", "default_parallel", "map_frames",
           "resolve_parallel", "resolve_workers"]

T = TypeVar("T")


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the OS has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


def resolve_workers(workers: int | None, count: int) -> int:
    """How many threads run ``count`` frames: ``workers`` (None: one per available core),
    never more than the frames."""
    want = available_cores() if workers is None else int(workers)
    return max(1, min(want, count))


def default_parallel() -> str:
    """What the workers of a frames axis are when the caller does not say
    (``RunOptions(parallel="auto")``, what ``radarsnn bench`` reports as ``parallel``):
    :func:`resolve_parallel` of ``"auto"`` in this process now.

    Examples
    --------
    >>> default_parallel() in ("threads", "processes")
    True
    """
    return resolve_parallel(RunOptions().parallel, 2)


def resolve_parallel(parallel: str, workers: int, program: object = None) -> str:
    """``"threads"`` or ``"processes"``: what ``workers`` workers of a frames axis are.

    ``"auto"`` takes processes (:mod:`backends.reference.frames_pool`) where the system can
    fork and forking is safe — this process runs no other thread, whose locks a forked
    copy could inherit held, or ``program`` already has its worker processes — and threads
    otherwise; ``"processes"`` takes them wherever the system can fork.  One worker is
    always the calling thread.

    Examples
    --------
    >>> resolve_parallel("threads", 4), resolve_parallel("processes", 1)
    ('threads', 'threads')
    """
    if workers <= 1 or parallel == "threads" or not fork_available():
        return "threads"
    if parallel == "processes" or threading.active_count() == 1:
        return "processes"
    return "processes" if program is not None and has_workers(program) else "threads"


class FrameStack:
    """Per key, the frames' arrays in one ``(F, *shape)`` array, as :func:`numpy.stack` gives.

    Parameters
    ----------
    count : int
        The number of frames.
    adopt : callable, optional
        ``adopt(value)``: the stack in shared memory that the first frame's ``value`` is a
        row of, which worker processes write their frames' rows into
        (:mod:`backends.reference.frames_rows`); that stack becomes the key's array, and a
        value that already is its row is not copied.  None (or no such stack): a new array.
    """

    def __init__(self, count: int,
                 adopt: Callable[[np.ndarray], np.ndarray | None] | None = None) -> None:
        self.count = count
        self._adopt = adopt
        self._arrays: dict[str, np.ndarray] | None = None
        self._keys: list[str] | None = None
        self._lock = threading.Lock()

    def put(self, index: int, values: Mapping[str, np.ndarray], *, where: str) -> None:
        """Copy frame ``index``'s ``values`` into their rows (threads put different rows).

        Raises
        ------
        SimulationError
            A frame's keys, shape or dtype differ from the first frame's (naming the key).
        """
        with self._lock:
            if self._arrays is None:
                self._arrays = {k: self._stack_for(np.asarray(v)) for k, v in values.items()}
                self._keys = list(values)
        arrays = self._arrays
        if set(values) != set(arrays):
            raise SimulationError(f"{where}: frame {index} has the values "
                                  f"{sorted(values)}, another frame {sorted(arrays)}; every "
                                  "frame must produce the same nodes")
        for k, v in values.items():
            v = np.asarray(v)
            out = arrays[k]
            if v.shape != out.shape[1:] or v.dtype != out.dtype:
                raise SimulationError(
                    f"{where}: node {k!r} is {v.dtype}{list(v.shape)} in frame {index} but "
                    f"{out.dtype}{list(out.shape[1:])} in another; a host implementation must "
                    "return the same dtype and shape for every frame", node=k)
            if not is_row(v, out, index):  # a worker wrote an adopted stack's row itself
                out[index] = v
        if index == 0:
            self._keys = list(values)

    def _stack_for(self, value: np.ndarray) -> np.ndarray:
        """The stack of a key whose first frame is ``value``: the shared stack it is a row
        of (``adopt``), or a new one."""
        stack = self._adopt(value) if self._adopt is not None else None
        if stack is not None and stack.shape == (self.count, *value.shape) \
                and stack.dtype == value.dtype:
            return stack
        return private_empty((self.count, *value.shape), value.dtype)

    def arrays(self) -> dict[str, np.ndarray]:
        """Every key's ``(F, *shape)`` array, in the first frame's key order."""
        if self._arrays is None:
            return {}
        return {k: self._arrays[k] for k in self._keys or self._arrays}


class SimStack:
    """Each spiking segment's per-frame :class:`SimResult` as one, like :meth:`SimResult.stack`.

    Outputs, first-spike steps and rasters go into :class:`FrameStack` rows as each frame
    is put; only the counts stay per frame until :meth:`results`.
    """

    def __init__(self, count: int,
                 adopt: Callable[[np.ndarray], np.ndarray | None] | None = None) -> None:
        self.count = count
        self._adopt = adopt
        self._light: list[Sequence[SimResult] | None] = [None] * count
        self._stacks: dict[int, tuple[FrameStack, FrameStack, FrameStack]] = {}
        self._rasters: list[bool] = []
        self._outputs: list[tuple[list[str], set[str]]] = []
        self._lock = threading.Lock()

    def put(self, index: int, sims: Sequence[SimResult], *, where: str,
            values: Mapping[str, np.ndarray] | None = None) -> None:
        """Frame ``index``'s segment results (each of one frame).

        An output that *is* the frame's entry of ``values`` (a decoded value the program
        keeps as is) is not copied again: :meth:`results` takes its rows from the stacked
        values given there, as the one-frame result shares the array.
        """
        with self._lock:
            stacks = [self._stacks.setdefault(k, tuple(FrameStack(self.count, self._adopt)
                                                       for _ in range(3)))
                      for k in range(len(sims))]
        shared = [[p for p, v in s.outputs.items() if values is not None and values.get(p) is v]
                  for s in sims]
        for (outputs, first, spikes), sim, same in zip(stacks, sims, shared, strict=True):
            outputs.put(index, {p: v for p, v in sim.outputs.items() if p not in same},
                        where=where)
            first.put(index, {k: v[0] for k, v in sim.first_spike_steps.items()}, where=where)
            if sim.spikes is not None:
                spikes.put(index, {k: v[0] for k, v in sim.spikes.items()}, where=where)
        self._light[index] = [replace(s, outputs={}, first_spike_steps={}, spikes=None)
                              for s in sims]
        if index == 0:  # rasters are recorded for every frame or none (SimResult.stack)
            self._rasters = [s.spikes is not None for s in sims]
            self._outputs = [(list(s.outputs), set(same)) for s, same in zip(sims, shared,
                                                                            strict=True)]

    def results(self, values: Mapping[str, np.ndarray] | None = None) -> list[SimResult]:
        """One result per segment over every frame (``values``: the stacked values whose
        arrays shared outputs take, see :meth:`put`)."""
        out = []
        for k in range(len(self._light[0] or ())):
            outputs, first, spikes = self._stacks[k]
            stacked = SimResult.stack([light[k] for light in self._light])
            names, same = self._outputs[k]
            own = outputs.arrays()
            decoded = {p: values[p] if p in same and values is not None else own[p]
                       for p in names}
            out.append(replace(stacked, outputs=decoded, first_spike_steps=first.arrays(),
                               spikes=spikes.arrays() if self._rasters[k] else None))
        return out


def map_frames(run: Callable[[int], T], count: int, workers: int,
               progress: Callable[[int, int], None] | None = None) -> None:
    """Call ``run(i)`` for every frame ``i < count`` on ``workers`` threads: the calling
    thread and ``workers − 1`` helpers, each taking the next frame not yet started.

    The calling thread works too, rather than waiting for a pool: its ``malloc`` arena
    (the main heap, for the main thread) recycles a frame's temporaries as a run of single
    frames does, so only the helpers' arenas page them in.  ``progress(done, count)`` is
    called on the calling thread, between its frames and at the end.  When a frame raises,
    no frame starts after it, and the exception of the earliest failing frame among those
    that ran is raised here.
    """
    if workers <= 1:
        for i in range(count):
            run(i)
            if progress is not None:
                progress(i + 1, count)
        return
    lock = threading.Lock()
    todo = iter(range(count))
    done: list[int] = []  # frames finished, reported by the calling thread
    failed: dict[int, BaseException] = {}
    stopped = [False]  # the calling thread left its loop (a progress callback raised)

    def take() -> int | None:
        with lock:
            return None if failed or stopped[0] else next(todo, None)

    def one(i: int) -> bool:
        try:
            run(i)
        except BaseException as err:  # noqa: BLE001 - the earliest is raised by the caller
            with lock:
                failed[i] = err
            return False
        with lock:
            done.append(i)
        return True

    def work() -> None:
        while (i := take()) is not None and one(i):
            pass

    def report(upto: int) -> int:
        with lock:
            now = len(done)
        if progress is not None:
            for n in range(upto + 1, now + 1):
                progress(n, count)
        return now

    helpers = [threading.Thread(target=work, name=f"radarsnn-frame-{k}", daemon=True)
               for k in range(1, workers)]
    for t in helpers:
        t.start()
    reported = 0
    try:
        while (i := take()) is not None and one(i):
            reported = report(reported)
    finally:
        with lock:
            stopped[0] = True
        for t in helpers:
            t.join()
    report(reported)
    if failed:  # the error of the earliest failing frame, as one thread would have raised it
        raise failed[min(failed)]
