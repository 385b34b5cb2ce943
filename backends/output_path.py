"""Output paths: refuse, before any work, a path no file (or folder) can be written to.

Every writer of radarsnn calls :func:`check_output` on the path it was given: a device such
as ``/dev/null``, a pipe, a socket, a folder given for a file (a file for a folder), a NUL
byte, an empty name, a file name ending in ``/`` and a name the system refuses are one
:class:`~ir.errors.ArtifactError` line naming the path and what to give instead — never a
traceback, never a file written beside a device, never a device replaced by a file.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ir.errors import ArtifactError
from ir.model import short_repr

__all__ = ["check_output"]


def check_output(path: str | os.PathLike, *, folder: bool = False) -> Path:
    """``path`` as a :class:`~pathlib.Path`, if a writer may create or replace a file there.

    Parameters
    ----------
    path : str or path-like
    folder : bool
        The output is a folder (else a regular file).

    Raises
    ------
    ArtifactError
        An empty name, a NUL byte, a file name ending in ``/``, a name the system
        refuses (too long, a file used as a folder), or an existing entry of another
        kind: a device such as ``/dev/null``, a pipe, a folder for a file (a file for
        a folder).  The message names the path and what to give instead.

    Examples
    --------
    >>> check_output("out/x.npz")
    PosixPath('out/x.npz')
    >>> check_output("/dev/null")
    Traceback (most recent call last):
    ir.errors.ArtifactError: output '/dev/null' exists and is not a regular file (a character \
device); give the path of a file to create or replace
    """
    text = os.fsdecode(os.fspath(path))
    shown = short_repr(text)
    kind = "folder" if folder else "file"
    if not text.strip():
        raise ArtifactError(f"output {shown} is empty; give the path of a {kind}")
    if "\0" in text:
        raise ArtifactError(f"output {shown} contains a NUL byte; give a path without one")
    if not folder and text.endswith(("/", os.sep)):
        raise ArtifactError(f"output {shown} ends with a path separator; give a file name")
    try:
        mode = os.stat(text).st_mode
    except FileNotFoundError:
        return Path(text)
    except OSError as exc:  # a name too long, a file used as a folder, a loop of links
        raise ArtifactError(f"output {shown} cannot be used ({exc.strerror}); give another "
                            f"path of a {kind}") from None
    if folder and not stat.S_ISDIR(mode):
        raise ArtifactError(f"output {shown} exists and is not a folder; give the path of a "
                            "folder to create or replace")
    if not folder and not stat.S_ISREG(mode):
        raise ArtifactError(f"output {shown} exists and is not a regular file "
                            f"(a {_KINDS.get(stat.S_IFMT(mode), 'special file')}); give the "
                            "path of a file to create or replace")
    return Path(text)


_KINDS = {stat.S_IFDIR: "folder", stat.S_IFCHR: "character device", stat.S_IFBLK: "block device",
          stat.S_IFIFO: "pipe", stat.S_IFSOCK: "socket"}
