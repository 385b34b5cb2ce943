"""Crash-safe writes: a file, or a whole directory, is there complete or not at all.

:func:`write_atomic` writes a file's bytes to a hidden sibling ``.NAME.PID-TOKEN.tmp``
(flushed to the disk with ``fsync`` when ``durable``) and renames it over ``NAME``.
:func:`replace_directory` does the same for a directory: the new tree is written into a
hidden sibling ``.NAME.PID-TOKEN.saving``, every file and folder of it synced, and then
*exchanged* with the old directory in one atomic ``renameat2(RENAME_EXCHANGE)`` (Linux);
the old tree, now under the temporary name, is removed afterwards.  A process killed at any
point therefore leaves the old or the new directory at ``NAME``, never neither and never a
mixture.  Where the exchange is not available (another OS, a file system without it) the
old directory is first renamed aside to ``.NAME.PID-TOKEN.old`` and the new one renamed
into place: a kill between those two renames leaves the old tree beside ``NAME``.

Replacing deletes only what an earlier write put there: the caller of
:func:`replace_directory` names those entries (``owned``, at every depth), anything else in
the old directory is refused or carried into the new one (``keep``;
:mod:`backends.atomic_owned`).  :func:`check_output`
refuses a path no file (or folder) can be written to: a device such as ``/dev/null``, a
pipe, a folder given for a file, a NUL byte.

A failed write (a full disk, a read-only folder) removes its temporary before the
error propagates; temporaries of *dead* processes (a kill, a power cut) are removed
by the next write to the same name.  Temporaries whose process is still running
(a concurrent writer) are left alone.

Examples
--------
>>> import tempfile
>>> with tempfile.TemporaryDirectory() as tmp:
...     out = Path(tmp) / "art"
...     _ = replace_directory(out, lambda d: write_file(d / "a.txt", b"old"),
...                           owned=lambda d: {"a.txt"})
...     _ = replace_directory(out, lambda d: write_file(d / "b.txt", b"new"),
...                           owned=lambda d: {"a.txt"})
...     sorted(p.name for p in Path(tmp).iterdir()), (out / "b.txt").read_bytes()
(['art'], b'new')
"""

from __future__ import annotations

import ctypes
import errno
import os
import secrets
import shutil
import stat
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import TypeVar

from backends.atomic_owned import carry_foreign, check_replaceable
from backends.output_path import check_output
from ir.errors import ArtifactError

__all__ = ["check_output", "replace_directory", "stale_temporaries", "write_atomic",
           "write_atomic_files", "write_file"]  # check_output: from backends.output_path

T = TypeVar("T")

_CHUNK = 1 << 24  # bytes per os.write call
_RENAME_EXCHANGE = 2  # <linux/fs.h>
_AT_FDCWD = -100
_SUFFIXES = (".tmp", ".saving", ".old")


def _renameat2():
    try:
        return ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):  # not glibc/Linux
        return None


_RENAMEAT2 = _renameat2()


def write_file(path: Path, data: bytes, *, sync: bool = True) -> None:
    """Create ``path`` (it must not exist) holding ``data``, synced to the disk if ``sync``.

    Raises
    ------
    OSError
        If the file cannot be created or written (the partial file is removed).
    """
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o644)
    try:
        view = memoryview(data)
        while view:
            view = view[_write(fd, view[:_CHUNK]):]
        if sync:
            os.fsync(fd)
    except BaseException:
        os.close(fd)
        _unlink(path)
        raise
    os.close(fd)


def _write(fd: int, chunk: memoryview) -> int:
    """One ``os.write`` (the point where tests simulate a full disk)."""
    return os.write(fd, chunk)


def _unlink(path: Path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def _fsync_dir(path: Path) -> None:
    """Sync a directory's entries (no-op where directories cannot be opened, e.g. Windows)."""
    flag = getattr(os, "O_DIRECTORY", None)
    if flag is None:
        return
    fd = os.open(path, os.O_RDONLY | flag)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _temp_name(target: Path, suffix: str) -> Path:
    return target.with_name(f".{target.name}.{os.getpid()}-{secrets.token_hex(4)}{suffix}")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True  # another thread of this process may be writing
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):  # OverflowError: no such pid can exist
        return False
    except OSError:  # EPERM: someone else's live process
        return True
    return True


def stale_temporaries(target: Path) -> list[Path]:
    """The temporaries of ``target`` left by processes that no longer run.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     (Path(tmp) / ".out.999999999-ab12cd34.saving").mkdir()
    ...     [p.name for p in stale_temporaries(Path(tmp) / "out")]
    ['.out.999999999-ab12cd34.saving']
    """
    prefix = f".{target.name}."
    found = []
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return []
    for entry in entries:
        name = entry.name
        if not name.startswith(prefix) or not name.endswith(_SUFFIXES):
            continue
        pid, _, token = name[len(prefix):].rsplit(".", 1)[0].partition("-")
        if pid.isascii() and pid.isdigit() and len(token) == 8 and not _alive(int(pid)):
            found.append(target.parent / name)
    return sorted(found)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        _unlink(path)


def write_atomic(path: Path, data: bytes, *, durable: bool = False) -> None:
    """Write ``data`` to a hidden temporary beside ``path``, then rename it over ``path``.

    Parameters
    ----------
    path : Path
    data : bytes
    durable : bool
        Also ``fsync`` the file before the rename and the folder after it, so the
        new content survives a power cut (a few milliseconds per file; without it
        the write is still atomic for readers and against a crash of the process).

    Raises
    ------
    ArtifactError
        ``path`` is no place for a file (:func:`check_output`: a device, a folder…).
    OSError
        If the file cannot be written (the caller wraps it); the temporary is
        removed and ``path`` keeps its previous content.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     write_atomic(Path(tmp) / "f", b"x")
    ...     write_atomic(Path(tmp) / "f", b"y")
    ...     [p.name for p in Path(tmp).iterdir()], (Path(tmp) / "f").read_bytes()
    (['f'], b'y')
    """
    write_atomic_files({path: data}, durable=durable)


def write_atomic_files(files: Mapping[Path, bytes], *, durable: bool = False) -> None:
    """:func:`write_atomic` for several files: each is renamed into place only once all are
    written, so a full disk changes none of them.

    Raises
    ------
    ArtifactError, OSError
        As :func:`write_atomic`; every temporary is removed (a failed write changes no
        file; a failed rename, after the others, leaves those renamed before it).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     write_atomic_files({Path(tmp) / "a.nir": b"x", Path(tmp) / "a.json": b"{}"})
    ...     sorted(p.name for p in Path(tmp).iterdir())
    ['a.json', 'a.nir']
    """
    paths = {check_output(path): data for path, data in files.items()}
    done: list[tuple[Path, Path]] = []
    try:
        for path, data in paths.items():
            for stale in stale_temporaries(path):
                _remove(stale)
            tmp = _temp_name(path, ".tmp")
            write_file(tmp, data, sync=durable)
            done.append((tmp, path))
        for tmp, path in done:
            os.replace(tmp, path)
    except BaseException:
        for tmp, _ in done:
            _unlink(tmp)
        raise
    if durable:
        for folder in dict.fromkeys(path.parent for path in paths):
            _fsync_dir(folder)


def _sync_tree(root: Path) -> None:
    """``fsync`` every file and directory below ``root`` (files first, then their folder)."""
    for folder, _, files in os.walk(root, topdown=False):
        for name in files:
            path = os.path.join(folder, name)
            if not stat.S_ISREG(os.lstat(path).st_mode):  # a link, a FIFO (open would block)
                continue
            fd = os.open(path, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        _fsync_dir(Path(folder))


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap the paths ``a`` and ``b``; False where the system cannot."""
    if _RENAMEAT2 is None:
        return False
    if _RENAMEAT2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def replace_directory(target: str | Path, fill: Callable[[Path], T], *,
                      owned: Callable[[Path], Iterable[str]], keep: bool = False,
                      durable: bool = True) -> T:
    """Build a new directory with ``fill`` and put it in the place of ``target`` atomically.

    Parameters
    ----------
    target : str or Path
        The directory to create or replace (symbolic links are resolved first).
    fill : callable
        ``fill(folder)`` writes the new tree into the empty ``folder`` (the
        temporary); its return value is returned.  Files written with
        :func:`write_file` or otherwise are all synced before the swap.
    owned : callable
        ``owned(directory)`` gives the relative paths (``a``, ``a/b``; files and
        folders) of what an earlier save wrote into the existing ``target``: all that
        replacing it may delete.  A folder's content is looked at only when the
        folder is owned.
    keep : bool
        What to do with the other (foreign) entries of ``target``: refuse to replace
        it (False), or keep them, hard-linked (or copied) into the new tree at the
        same place before the swap (True; one that the new tree also writes is
        refused).
    durable : bool
        ``fsync`` every file and folder of the new tree before the swap, so it
        survives a power cut (without it the swap is still atomic for readers and
        against a killed process).

    Returns
    -------
    object
        What ``fill`` returned.

    Raises
    ------
    ArtifactError
        ``target`` is a file, holds foreign entries (unless ``keep``), or is the
        working directory.
    OSError
        A file-system failure; the temporary is removed and ``target`` is unchanged.
    """
    shown = target
    target = Path(os.path.realpath(target))
    exists = os.path.lexists(target)
    if exists and not target.is_dir():
        raise ArtifactError(f"cannot save into {shown}: it exists and is not a directory")
    mine = set(owned(target)) if exists else None
    check_replaceable(target, mine, shown, keep)  # before the work: refuse early
    target.parent.mkdir(parents=True, exist_ok=True)
    for stale in stale_temporaries(target):
        _remove(stale)
    tmp = _temp_name(target, ".saving")
    os.mkdir(tmp)
    try:
        result = fill(tmp)
        carry_foreign(target, tmp, check_replaceable(target, mine, shown, keep), shown)  # as now
        if durable:
            _sync_tree(tmp)
        if not exists:
            os.rename(tmp, target)  # fails (ENOTEMPTY/EEXIST) if one appeared meanwhile
        elif not _exchange(tmp, target):
            aside = _temp_name(target, ".old")
            os.rename(target, aside)
            try:
                os.rename(tmp, target)
            except BaseException:
                os.rename(aside, target)
                raise
            tmp = aside
    except BaseException:
        _remove(tmp)
        raise
    if durable:
        _fsync_dir(target.parent)
    _remove(tmp)  # the old tree (when there was one); what was kept lives on in the new one
    return result
