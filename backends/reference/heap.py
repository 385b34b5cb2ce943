"""Keep freed arrays in the process's heap: glibc's malloc thresholds where its own rule ends.

A frame of the closed form allocates and frees arrays of a few MB.  glibc's malloc serves an
allocation above its *mmap threshold* with a fresh mapping that the kernel zero-fills page
by page, and gives memory back to the kernel once more than its *trim threshold* lies free
at the top of a heap.  It raises both thresholds itself — the mmap threshold to the size of
the largest mapped block freed so far, up to :data:`MMAP_THRESHOLD_BYTES` (its
``DEFAULT_MMAP_THRESHOLD_MAX`` on 64-bit systems), the trim threshold to twice that — but
only after such a block is freed, and a worker thread's own heap is trimmed against the
same threshold.  Until then every frame pays the kernel again: page faults, zero-filling and,
with threads, the mappings given back while the other thread runs.  That is the *system*
CPU time ``radarsnn bench`` reports.

:func:`hold_freed_memory` sets the mmap threshold to the most glibc's rule reaches
(``mallopt(M_MMAP_THRESHOLD, 32 MiB)``) and the trim threshold above what glibc's rule would
give (``mallopt(M_TRIM_THRESHOLD, 256 MiB)``, not 64 MiB), as the ``MALLOC_MMAP_THRESHOLD_`` /
``MALLOC_TRIM_THRESHOLD_`` environment variables would at start-up, so a frame reuses the
memory the previous frame freed.  The trim threshold is above the working set of one call of
the step engine or of a compile on a radar frame (about 100 MB, in and out of the heap a few
times a call): at 64 MiB the heap gave it back to the kernel and faulted it in again every
call (about 17 000 page faults per step-mode frame of the carrada preset; none at 256 MiB).
It changes how the *whole process* allocates — a heap keeps up to 256 MiB of freed memory for
reuse instead of returning it — so the library never calls it on its own: the ``radarsnn``
command calls it when it starts (it owns its process), and a program that runs many frames
calls it once.
Results are the same bit for bit either way; only where the memory comes from changes.
On a C library other than glibc (macOS, Windows, musl) it does nothing and says so.

Examples
--------
>>> done = hold_freed_memory()
>>> want = (MMAP_THRESHOLD_BYTES, TRIM_THRESHOLD_BYTES) if done else None
>>> isinstance(done, bool), held() == want
(True, True)
>>> MMAP_THRESHOLD_BYTES, TRIM_THRESHOLD_BYTES
(33554432, 268435456)
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import sys

from ir.errors import SimulationError

__all__ = ["MMAP_THRESHOLD_BYTES", "TRIM_THRESHOLD_BYTES", "held", "hold_freed_memory"]

_log = logging.getLogger(__name__)

#: glibc's ``DEFAULT_MMAP_THRESHOLD_MAX`` on 64-bit systems: the most its own rule raises the
#: mmap threshold to.
MMAP_THRESHOLD_BYTES = 32 * 2**20
#: Above the working set of a step-mode frame or a compile (module docstring); glibc's own
#: rule stops at twice the mmap threshold.
TRIM_THRESHOLD_BYTES = 256 * 2**20
#: ``mallopt`` parameters of ``<malloc.h>``.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: The thresholds :func:`hold_freed_memory` set in this process (None: never called, or not glibc).
_held: tuple[int, int] | None = None


def hold_freed_memory(mmap_threshold_bytes: int = MMAP_THRESHOLD_BYTES,
                      trim_threshold_bytes: int = TRIM_THRESHOLD_BYTES) -> bool:
    """Set glibc's mmap and trim thresholds (module docstring); True if both were set.

    Parameters
    ----------
    mmap_threshold_bytes : int
        Allocations up to this size come from a heap, not a fresh mapping.
    trim_threshold_bytes : int
        A heap keeps up to this much freed memory at its top for reuse.

    Returns
    -------
    bool
        False when the C library is not glibc (nothing is changed).

    Raises
    ------
    SimulationError
        If a threshold is not a whole number of bytes in ``[1, 2**31 - 1]`` (``mallopt``
        takes a C ``int``).
    """
    for name, value, default in (
            ("mmap_threshold_bytes", mmap_threshold_bytes, MMAP_THRESHOLD_BYTES),
            ("trim_threshold_bytes", trim_threshold_bytes, TRIM_THRESHOLD_BYTES)):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 < value < 2**31:
            raise SimulationError(f"hold_freed_memory: {name}={value!r} is not a whole number "
                                  f"of bytes in [1, 2**31 - 1]; the default is {default}")
    libc = _glibc()
    if libc is None:
        _log.info("hold_freed_memory: not glibc (%s); malloc left as it is", sys.platform)
        return False
    done = (libc.mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold_bytes)) == 1
            and libc.mallopt(_M_TRIM_THRESHOLD, int(trim_threshold_bytes)) == 1)
    _log.info("hold_freed_memory: mmap threshold %d B, trim threshold %d B (%s)",
              mmap_threshold_bytes, trim_threshold_bytes, "set" if done else "refused")
    global _held
    if done:
        _held = (int(mmap_threshold_bytes), int(trim_threshold_bytes))
    return done


def held() -> tuple[int, int] | None:
    """``(mmap, trim)`` thresholds in bytes that :func:`hold_freed_memory` set in this process,
    or None if it never did (the bench records this next to its figures)."""
    return _held


def _glibc() -> ctypes.CDLL | None:
    """The running glibc, or None."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version.restype = ctypes.c_char_p
        libc.gnu_get_libc_version()
    except (OSError, AttributeError):
        return None
    libc.mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    libc.mallopt.restype = ctypes.c_int
    return libc
