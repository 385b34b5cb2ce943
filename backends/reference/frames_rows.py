"""Result stacks in shared memory, whose rows worker processes write their frames into.

A frames axis on worker processes (:mod:`backends.reference.frames_workers`) ends in one
``(F, *shape)`` array per value (:class:`~backends.reference.frames_run.FrameStack`).  When
the parent knows the arrays a frame gives (their *layout*: the shapes and dtypes of the
previous frame's), it allocates those stacks in shared memory before the frames start, and
each worker writes its frame's arrays straight into their row: no copy goes through a slot
and none is made by the parent, which only collects the light records.

A stack lives in a :class:`SharedBlock`, an anonymous file (``memfd_create``) mapped by the
parent and, by file descriptor passed once over the worker's pipe, by every worker.  While
the process holds freed memory (:func:`backends.reference.heap.hold_freed_memory`) a stack
its user frees keeps its block — up to :data:`~backends.reference.frames_memory.KEPT_STACK_BYTES`
in all — for the next stack of the same size, so a loop of calls maps and pages in its blocks
once; a block dropped is forgotten by the workers too.  Where ``memfd_create`` is missing,
nothing is allocated here and the frames travel through the slots.

Examples
--------
>>> import numpy as np
>>> stacks = RowStacks()
>>> rows = stacks.rows(3, [((2,), np.dtype(np.int16))]) if memfd_available() else None
>>> rows is None or (rows.arrays[0].shape, rows.arrays[0].dtype.name) == ((3, 2), "int16")
True
>>> rows is None or rows.stack_of(rows.arrays[0][1]) is rows.arrays[0]
True
>>> stacks.close()
"""

from __future__ import annotations

import itertools
import mmap
import os
import threading
import weakref
from collections.abc import Sequence
from math import prod

import numpy as np

from backends.reference.frames_memory import KEPT_STACK_BYTES
from backends.reference.heap import held

__all__ = ["Rows", "RowStacks", "SharedBlock", "is_row", "memfd_available"]

#: (shape, dtype) of each array of a frame's result, in :func:`strip_result` order.
Layout = Sequence[tuple[tuple[int, ...], np.dtype]]


def memfd_available() -> bool:
    """Whether shared stacks can be made here (Linux's ``memfd_create``)."""
    return hasattr(os, "memfd_create")


class SharedBlock:
    """``size`` bytes of an anonymous file, mapped shared; workers know it by ``id``.

    The file descriptor is kept only until every worker has been sent it
    (:meth:`close_fd`); the mapping stays.
    """

    def __init__(self, block_id: int, size: int) -> None:
        self.id, self.size = block_id, size
        self.fd = os.memfd_create(f"radarsnn-rows-{block_id}", getattr(os, "MFD_CLOEXEC", 0))
        os.ftruncate(self.fd, size)
        self.buffer = mmap.mmap(self.fd, size)

    def close_fd(self) -> None:
        """Close the file descriptor (the mapping, here and in the workers, stays)."""
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1


class Rows:
    """One call's stacks: ``arrays[j]`` holds array ``j`` of every frame's result.

    Attributes
    ----------
    arrays : list of ndarray
        ``(count, *shape_j)`` arrays in shared memory.
    blocks : list of SharedBlock
        Their blocks (``blocks[j].id`` is what a worker is told).
    layout : list of (shape, dtype)
        The layout they were made for.
    """

    def __init__(self, arrays: list[np.ndarray], blocks: list[SharedBlock],
                 layout: Layout) -> None:
        self.arrays, self.blocks, self.layout = arrays, blocks, list(layout)
        self._by_base = {id(a.base): a for a in arrays}

    def spec(self) -> list[tuple[int, tuple[int, ...], np.dtype]]:
        """What a worker needs to write its rows: (block id, shape, dtype) per array."""
        return [(b.id, a.shape, a.dtype) for b, a in zip(self.blocks, self.arrays, strict=True)]

    def row_views(self, index: int) -> list[np.ndarray]:
        """Frame ``index``'s row of every stack (as :func:`restore_result` takes them)."""
        return [a[index] for a in self.arrays]

    def stack_of(self, value: np.ndarray) -> np.ndarray | None:
        """The stack ``value`` is a row of (by its base), or None.

        :class:`~backends.reference.frames_run.FrameStack` adopts that stack as its own
        array instead of allocating one, and copies nothing into it.
        """
        return self._by_base.get(id(getattr(value, "base", None)))


def is_row(value: np.ndarray, stack: np.ndarray, index: int) -> bool:
    """Whether ``value`` is exactly row ``index`` of ``stack`` (same memory, shape, strides)."""
    row = stack[index]
    return (isinstance(value, np.ndarray) and value.shape == row.shape
            and value.dtype == row.dtype and value.strides == row.strides
            and value.__array_interface__["data"][0] == row.__array_interface__["data"][0])


class RowStacks:
    """The shared blocks of one pool: made on demand, the freed ones kept for reuse.

    ``new`` lists the blocks made since the workers were last told (the pool sends their
    descriptors), ``dropped`` the ids of blocks let go (the workers unmap them).
    """

    def __init__(self, limit_bytes: int = KEPT_STACK_BYTES) -> None:
        self.limit = limit_bytes
        self.new: list[SharedBlock] = []
        self.dropped: list[int] = []
        self._free: dict[int, list[SharedBlock]] = {}
        self._free_bytes = 0
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._closed = False

    def rows(self, count: int, layout: Layout) -> Rows | None:
        """Stacks of ``count`` rows for ``layout``, or None (no ``memfd_create``, or an
        array of Python objects)."""
        if not memfd_available() or any(np.dtype(d).hasobject for _, d in layout):
            return None
        arrays, blocks = [], []
        for shape, dtype in layout:
            array, block = self._empty((count, *shape), np.dtype(dtype))
            arrays.append(array)
            blocks.append(block)
        return Rows(arrays, blocks, layout)

    def _empty(self, shape: tuple[int, ...], dtype: np.dtype) -> tuple[np.ndarray, SharedBlock]:
        size = max(1, prod(shape) * dtype.itemsize)
        with self._lock:
            kept = self._free.get(size)
            block = kept.pop() if kept else None
            if block is not None:
                self._free_bytes -= size
        if block is None:
            block = SharedBlock(next(self._ids), size)
            self.new.append(block)
        flat = np.frombuffer(block.buffer, dtype=dtype, count=prod(shape))
        weakref.finalize(flat, self._freed, block, held() is not None).atexit = False
        return flat.reshape(shape), block

    def _freed(self, block: SharedBlock, keep: bool) -> None:
        """A stack's last view is gone: keep its block for reuse, or let it go."""
        with self._lock:
            if keep and not self._closed and self._free_bytes + block.size <= self.limit:
                self._free.setdefault(block.size, []).append(block)
                self._free_bytes += block.size
                return
            self.dropped.append(block.id)
        block.close_fd()

    def take_new(self) -> list[SharedBlock]:
        """The blocks made since the last call (their descriptors go to the workers)."""
        with self._lock:
            new, self.new = self.new, []
        return new

    def take_dropped(self) -> list[int]:
        """The ids let go since the last call (the workers forget them)."""
        with self._lock:
            dropped, self.dropped = self.dropped, []
        return dropped

    def close(self) -> None:
        """Let every kept block go (stacks still in use stay valid: they hold their maps)."""
        with self._lock:
            self._closed = True
            free, self._free, self._free_bytes = self._free, {}, 0
        for blocks in free.values():
            for block in blocks:
                block.close_fd()
