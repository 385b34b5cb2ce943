"""Simulated file-system faults for tests: a disk that fills up after a given number of bytes.

:class:`DiskFull` patches the three ways the code under test writes bytes — ``os.write``
(on descriptors of files below the root), ``builtins.open`` and ``io.open`` (files opened for
writing below the root: ``pathlib``, ``zipfile``, ``np.savez``) — so that once ``free`` bytes
have been written below ``root`` every further write writes what still fits and raises
``OSError(errno.ENOSPC)`` (or another errno), as a full disk does.  Reads and files
elsewhere are untouched.
"""

from __future__ import annotations

import builtins
import errno
import io
import os
import random
import signal
import stat
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest


class _Budget:
    def __init__(self, free: int, code: int) -> None:
        self.left, self.code, self.failures = free, code, 0

    def take(self, n: int) -> int:
        """Bytes of ``n`` that still fit (the budget shrinks by that much)."""
        got = max(0, min(n, self.left))
        self.left -= got
        return got

    def error(self) -> OSError:
        self.failures += 1
        return OSError(self.code, os.strerror(self.code))


class _LimitedFile:
    """A file object whose ``write`` stops at the budget (everything else delegated)."""

    def __init__(self, f, budget: _Budget) -> None:
        self._f, self._budget = f, budget

    def write(self, data) -> int:
        view = memoryview(data).cast("B") if not isinstance(data, str) else data
        n = self._budget.take(len(view))
        self._f.write(view[:n])
        if n < len(view):
            raise self._budget.error()
        return n

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self._f.close()

    def __iter__(self):
        return iter(self._f)

    def __getattr__(self, name: str):
        return getattr(self._f, name)


class DiskFull:
    """``with disk_full(free=100): ...`` — writes below ``root`` fail after 100 bytes."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, root: Path) -> None:
        self._monkeypatch, self._root = monkeypatch, str(Path(root).resolve())

    def _under(self, path: object) -> bool:
        try:
            return os.path.realpath(os.fsdecode(path)).startswith(self._root)
        except (TypeError, ValueError):
            return False

    @contextmanager
    def __call__(self, free: int, code: int = errno.ENOSPC) -> Iterator[_Budget]:
        budget = _Budget(free, code)
        real_write, real_open = os.write, io.open

        def write(fd: int, data) -> int:
            try:
                target = os.readlink(f"/proc/self/fd/{fd}")
            except OSError:
                target = ""
            if not self._under(target):
                return real_write(fd, data)
            view = memoryview(data).cast("B")
            n = budget.take(len(view))
            if n == 0 and len(view):
                raise budget.error()
            return real_write(fd, view[:n])  # a short write; the next one raises

        def open_(file, mode="r", *args, **kwargs):
            f = real_open(file, mode, *args, **kwargs)
            if any(c in mode for c in "wax+") and not isinstance(file, int) and self._under(file):
                return _LimitedFile(f, budget)
            return f

        with self._monkeypatch.context() as m:
            m.setattr(os, "write", write)
            m.setattr(io, "open", open_)
            m.setattr(builtins, "open", open_)
            yield budget


def device_node(folder: Path) -> Path | None:
    """A character device like ``/dev/null`` at ``folder/null`` (None where it cannot be made).

    Tests of output paths use it, never ``/dev/null`` itself: a writer that renamed its
    file over the path would replace the system's null device with a regular file.
    """
    path = Path(folder) / "null"
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except (AttributeError, OSError):  # not root, or no mknod on this system
        return None
    return path


def listing(root: Path) -> list[str]:
    """Every path below ``root`` (relative, sorted): what a fault may have left behind."""
    return sorted(str(p.relative_to(root)) for p in Path(root).rglob("*"))


def tree_bytes(root: Path) -> dict[str, bytes]:
    """``{relative path: bytes}`` of every file below ``root``."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(Path(root).rglob("*"))
            if p.is_file()}


__all__ = ["DiskFull", "device_node", "fault_chain", "kill_while_saving", "listing",
           "tree_bytes"]


def fault_chain(name: str) -> tuple:
    """A tiny chain (window, power, CA-CFAR over 8 cells) and its input, for save tests."""
    import numpy as np

    from ir import Graph

    graph = Graph.from_dict({"name": name, "nodes": [
        {"id": "a", "op": "input", "shape": {"range": 8}},
        {"id": "w", "op": "window", "input": "a", "axis": "range", "kind": "hann"},
        {"id": "m", "op": "magnitude", "input": "w", "kind": "square"},
        {"id": "c", "op": "cfar", "input": "m", "kind": "ca", "guard": 0, "train": 1,
         "alpha": 1.5},
        {"id": "o", "op": "output", "input": "c"}]})
    return graph, {"a": np.linspace(-1.0, 1.0, 8)}


def _slow_disk(delay_s: float) -> None:
    """Make each file write of this (forked) process take ``delay_s / 8`` longer, as on a
    slow disk.

    On a RAM-backed ``/tmp`` writing costs almost nothing and a save's temporary lives
    for a sliver of it, so random kills would rarely land while it exists.
    """
    import backends.atomic as atomic

    write = atomic._write

    def slow(fd, chunk):
        time.sleep(delay_s / 8)
        return write(fd, chunk)

    atomic._write = slow


def kill_while_saving(tmp_path: Path, versions: list, save_one, check, kills: int,
                      seed: int) -> list[str]:
    """Fork a child that saves ``versions`` in turn forever; SIGKILL it at random moments.

    ``save_one(version, target)`` saves into ``target`` (a directory); ``check(target)``
    names the state a kill left (it raises if that state is broken).  Returns the names.
    """
    import backends.atomic as atomic

    rng = random.Random(seed)
    target = tmp_path / "target"
    save_one(versions[0], target)
    start = time.perf_counter()
    save_one(versions[1], target)
    period = time.perf_counter() - start
    seen, interrupted = [], 0
    for _ in range(kills):
        ready_r, ready_w = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns into pytest
            code = 0
            try:
                os.close(ready_r)
                _slow_disk(period)
                i = rng.randrange(2)
                save_one(versions[i % 2], target)  # warm: a fresh fork may start slowly
                os.write(ready_w, b"1")  # saving in a loop now
                while True:
                    i += 1
                    save_one(versions[i % 2], target)
            except BaseException:  # noqa: BLE001 - reported to the parent by the exit code
                code = 3
            finally:
                os._exit(code)
        os.close(ready_w)
        os.read(ready_r, 1)  # kill only a child that saves in its loop
        os.close(ready_r)
        time.sleep(rng.uniform(0.0, 3 * period))
        os.kill(pid, signal.SIGKILL)
        _, status = os.waitpid(pid, 0)
        assert os.WIFSIGNALED(status), f"the saving child failed (status {status})"
        interrupted += bool(atomic.stale_temporaries(target))  # killed mid-save: temporary left
        seen.append(check(target))
    assert interrupted >= kills // 4, f"only {interrupted} of {kills} kills hit a save"
    return seen
