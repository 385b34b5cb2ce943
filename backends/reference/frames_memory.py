"""Memory for the frames of a program run: stacks of their own, and slots shared with workers.

A frames axis (:mod:`backends.reference.frames_run`) stacks every frame's values into one
array per node (:func:`private_empty`): a mapping of its own, paged in once.  While the
process holds freed memory for reuse (:func:`backends.reference.heap.hold_freed_memory`,
which the ``radarsnn`` command calls), the mapping of a stack that is freed is kept — up to
:data:`KEPT_STACK_BYTES` in all — for the next stack of the same size, as the heap keeps a
frame's temporaries: a loop over calls then pays the kernel's page faults and zero-filling
once, not on every call.  On worker processes
(:mod:`backends.reference.frames_pool`) a frame's arrays travel through a *slot*: a block
of anonymous shared memory (:func:`shared_empty`) that the parent and one forked worker
both map.  :func:`pack_arrays` copies arrays into a slot one after the other (each aligned
to 64 bytes) and returns a small header — offset, dtype and shape of each — which is all
that goes through the pipe; :func:`unpack_arrays` turns the header back into views of the
slot.  :func:`strip_result` and :func:`restore_result` take a frame's
:class:`~backends.reference.program.ProgramResult` apart into that list of arrays plus a
light record holding :class:`ArrayRef` markers, and put it back together (an array that
appears under several keys — a decoded output that is also a value — is packed once and
comes back as one array under every key).

Examples
--------
>>> import numpy as np
>>> slot = shared_empty((1024,), np.uint8)
>>> header, end = pack_arrays([np.arange(3.0), np.array([[True, False]])], slot)
>>> [a.tolist() for a in unpack_arrays(header, slot)], end
([[0.0, 1.0, 2.0], [[True, False]]], 66)
>>> pack_arrays([np.zeros(200)], slot)   # 1 600 bytes do not fit: nothing written
(None, 1600)
"""

from __future__ import annotations

import mmap
import multiprocessing
import os
import threading
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from math import prod

import numpy as np

from backends.reference.heap import held

__all__ = ["KEPT_STACK_BYTES", "ArrayRef", "fork_available", "pack_arrays", "packed_bytes",
           "private_empty", "restore_result", "shared_empty", "strip_result", "unpack_arrays"]

#: Alignment of each array in a slot (a cache line).
_ALIGN = 64
#: The most bytes of freed stacks' mappings kept for reuse (while freed memory is held).
KEPT_STACK_BYTES = 256 << 20


def fork_available() -> bool:
    """Whether worker processes can be forked here (they inherit the plans and buffers): the
    system can fork, and this process is not a daemonic one (a ``multiprocessing`` pool's
    worker, say), which may not have children."""
    return (hasattr(os, "fork") and "fork" in multiprocessing.get_all_start_methods()
            and not multiprocessing.current_process().daemon)


def shared_empty(shape: tuple[int, ...], dtype) -> np.ndarray:
    """An uninitialised array in anonymous shared memory (forked children write into it)."""
    dtype = np.dtype(dtype)
    count = prod(shape)
    buffer = mmap.mmap(-1, max(1, count * dtype.itemsize))
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape)


def private_empty(shape: tuple[int, ...], dtype) -> np.ndarray:
    """An uninitialised array in its own anonymous private mapping (huge pages asked for), or
    in the kept mapping of a freed one of the same size (module docstring).

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
    size = max(1, count * dtype.itemsize)
    buffer = _FREED.take(size)
    if buffer is None:
        buffer = mmap.mmap(-1, size, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
        if hasattr(mmap, "MADV_HUGEPAGE") and size >= 4 << 20:
            buffer.madvise(mmap.MADV_HUGEPAGE)  # as numpy asks for its own large arrays
    flat = np.frombuffer(buffer, dtype=dtype, count=count)
    if _FREED.keeps():  # on the array every view's .base is: freed only when no view is left
        weakref.finalize(flat, _FREED.give, size, buffer).atexit = False
    return flat.reshape(shape)


class _Freed:
    """Mappings of freed stacks kept for the next stacks of the same size (while the
    process holds freed memory, :func:`backends.reference.heap.hold_freed_memory`)."""

    def __init__(self, limit_bytes: int) -> None:
        self.limit = limit_bytes
        self._kept: dict[int, list[mmap.mmap]] = {}
        self._bytes = 0
        self._lock = threading.Lock()

    def keeps(self) -> bool:
        return held() is not None

    def take(self, size: int) -> mmap.mmap | None:
        with self._lock:
            kept = self._kept.get(size)
            if not kept:
                return None
            self._bytes -= size
            return kept.pop()

    def give(self, size: int, buffer: mmap.mmap) -> None:
        with self._lock:
            if self._bytes + size > self.limit:
                return
            self._kept.setdefault(size, []).append(buffer)
            self._bytes += size


_FREED = _Freed(KEPT_STACK_BYTES)


def _aligned(offset: int) -> int:
    return -(-offset // _ALIGN) * _ALIGN


def packed_bytes(arrays: Sequence[np.ndarray], start: int = 0) -> int:
    """The slot bytes :func:`pack_arrays` needs for ``arrays`` from offset ``start``."""
    end = start
    for a in arrays:
        end = _aligned(end) + a.nbytes
    return end


def pack_arrays(arrays: Sequence[np.ndarray], slot: np.ndarray, start: int = 0
                ) -> tuple[list[tuple[int, np.dtype, tuple[int, ...]]] | None, int]:
    """Copy ``arrays`` into the bytes of ``slot`` from offset ``start``.

    Returns the header (offset, dtype, shape per array) and the end offset; ``(None,
    bytes needed)`` when they do not fit or an array holds Python objects (nothing is
    written then).
    """
    end = packed_bytes(arrays, start)
    if end > slot.nbytes or any(a.dtype.hasobject for a in arrays):
        return None, end
    header, offset = [], start
    for a in arrays:
        offset = _aligned(offset)
        view = np.ndarray(a.shape, a.dtype, buffer=slot, offset=offset)
        np.copyto(view, a, casting="no")
        header.append((offset, a.dtype, a.shape))
        offset += a.nbytes
    return header, end


def unpack_arrays(header: Sequence[tuple[int, np.dtype, tuple[int, ...]]], slot: np.ndarray
                  ) -> list[np.ndarray]:
    """The arrays of a :func:`pack_arrays` header: views of ``slot`` (valid until it is
    written again)."""
    return [np.ndarray(shape, dtype, buffer=slot, offset=offset)
            for offset, dtype, shape in header]


@dataclass(frozen=True)
class ArrayRef:
    """Where an array of a stripped result went: its index in the packed list."""

    index: int


class _Refs:
    """Arrays collected once each (by identity), replaced by their :class:`ArrayRef`."""

    def __init__(self) -> None:
        self.arrays: list[np.ndarray] = []
        self._index: dict[int, ArrayRef] = {}
        self._held: list[object] = []  # keeps every seen object alive, so ids stay unique

    def of(self, mapping: Mapping[str, object] | None) -> dict[str, ArrayRef] | None:
        if mapping is None:
            return None
        out = {}
        for key, value in mapping.items():
            ref = self._index.get(id(value))
            if ref is None:
                ref = self._index[id(value)] = ArrayRef(len(self.arrays))
                self._held.append(value)
                self.arrays.append(np.asarray(value))
            out[key] = ref
        return out


def strip_result(result):
    """A frame's :class:`~backends.reference.program.ProgramResult` as ``(light,
    arrays)``: the same record with every array replaced by an :class:`ArrayRef`, and the
    arrays (each once).

    Examples
    --------
    >>> from backends.reference.program import ProgramResult
    >>> x = np.arange(2.0)
    >>> light, arrays = strip_result(ProgramResult(values={"a": x, "o": x}, outputs={"o": x}))
    >>> light.values, len(arrays)
    ({'a': ArrayRef(index=0), 'o': ArrayRef(index=0)}, 1)
    >>> back = restore_result(light, arrays)
    >>> back.values["a"] is back.outputs["o"]
    True
    """
    refs = _Refs()
    values, outputs, peaks = refs.of(result.values), refs.of(result.outputs), \
        refs.of(result.input_peaks)
    sims = [replace(s, outputs=refs.of(s.outputs), first_spike_steps=refs.of(
        s.first_spike_steps), spikes=refs.of(s.spikes)) for s in result.simulations]
    light = replace(result, values=values, outputs=outputs, input_peaks=peaks,
                    simulations=sims)
    return light, refs.arrays


def restore_result(light, arrays: Sequence[np.ndarray]):
    """:func:`strip_result` undone: the record with its arrays back (the same object for
    every key that shared one)."""
    def back(mapping: Mapping[str, ArrayRef] | None) -> dict[str, np.ndarray] | None:
        return None if mapping is None else {k: arrays[r.index] for k, r in mapping.items()}

    sims = [replace(s, outputs=back(s.outputs), first_spike_steps=back(s.first_spike_steps),
                    spikes=back(s.spikes)) for s in light.simulations]
    return replace(light, values=back(light.values), outputs=back(light.outputs),
                   input_peaks=back(light.input_peaks), simulations=sims)
