"""What every reader of a user's file checks first: a regular file, and a shape the port takes.

:func:`open_regular` opens without blocking (a FIFO named ``f3.npy`` is refused at once,
not waited on forever) and refuses anything but a regular file (devices, folders, FIFOs,
sockets); :func:`check_frame_shape` compares the shape a file *declares* (its header) with
the port's before the data is read or decoded, so a file can never make a reader allocate
more than the port could take.  Errors are :class:`ir.errors.RadarConfigError`.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Sequence
from pathlib import Path
from typing import BinaryIO

from ir.errors import RadarConfigError

__all__ = ["MAX_ARRAY_BYTES", "check_frame_shape", "open_regular", "pick", "shape_text"]

#: Most bytes one array read from a ``.npy``, ``.npz`` or ``.mat`` file may take: 4 GiB.
MAX_ARRAY_BYTES = 4 << 30


def open_regular(path: str | Path, what: str) -> BinaryIO:
    """``path`` opened for binary reading, if it is a regular file.

    Parameters
    ----------
    path : str or Path
    what : str
        Names the file in messages (``"{what}: no such file"``).

    Returns
    -------
    file
        A buffered binary reader (the caller closes it).

    Raises
    ------
    RadarConfigError
        Missing, unreadable, a NUL in the path, or not a regular file (checked on the
        opened descriptor, so the file cannot be swapped after the check).

    Examples
    --------
    >>> open_regular("/dev/null", "input x")
    Traceback (most recent call last):
    ...
    ir.errors.RadarConfigError: input x: not a regular file (a device, folder, FIFO or \
socket); give a file
    """
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)  # a FIFO: no wait
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise RadarConfigError(f"{what}: no such file") from None
    except (OSError, ValueError, TypeError) as err:  # ValueError: a NUL byte in the path
        raise RadarConfigError(f"{what}: cannot open it ({getattr(err, 'strerror', None) or err})"
                               ) from None
    try:
        regular = stat.S_ISREG(os.fstat(fd).st_mode)
        if regular:
            os.set_blocking(fd, True)
            return os.fdopen(fd, "rb")
    except OSError as err:
        os.close(fd)
        raise RadarConfigError(f"{what}: cannot read it ({err.strerror or err})") from None
    os.close(fd)
    raise RadarConfigError(f"{what}: not a regular file (a device, folder, FIFO or socket); "
                           "give a file")


def shape_text(shape: Sequence[int], limit: int = 60) -> str:
    """A shape as Python writes it, cut to ``limit`` characters (a forged header's 100 axes).

    Examples
    --------
    >>> shape_text((2, 3)), shape_text((1,) * 40)[-6:]
    ('(2, 3)', ', ...)')
    """
    text = repr(tuple(shape))
    return text if len(text) <= limit else text[:limit - 5].rsplit(",", 1)[0] + ", ...)"


def check_frame_shape(what: str, shape: Sequence[int],
                      frame_shape: Sequence[int] | None) -> None:
    """Refuse a declared ``shape`` that is neither ``frame_shape`` nor frames of it.

    Parameters
    ----------
    what : str
        Names the file (and member or variable) in the message.
    shape : sequence of int
        The shape the file declares, before its data is read.
    frame_shape : sequence of int, optional
        One frame of the port the file is for; None: not known, nothing checked.

    Raises
    ------
    RadarConfigError
        ``shape`` is not ``frame_shape`` or ``(frames, *frame_shape)``.

    Examples
    --------
    >>> check_frame_shape("x.npy", (5, 2, 3), (2, 3))
    >>> check_frame_shape("x.npy", (10**9, 7), (2, 3))
    Traceback (most recent call last):
    ...
    ir.errors.RadarConfigError: x.npy: declares shape (1000000000, 7), but the port takes \
(2, 3) (one frame) or (frames, 2, 3); give the port's shape (nothing was read)
    """
    if frame_shape is None:
        return
    shape, frame = tuple(shape), tuple(frame_shape)
    if shape == frame or (len(shape) == len(frame) + 1 and shape[1:] == frame):
        return
    framed = "(frames, " + shape_text(frame)[1:].rstrip(",)") + ")" if frame else "(frames,)"
    raise RadarConfigError(f"{what}: declares shape {shape_text(shape)}, but the port takes "
                           f"{shape_text(frame)} (one frame) or {framed}; give the port's "
                           "shape (nothing was read)")


def pick(path: Path, names: list[str], key: str | None, kind: str, how: str) -> str:
    """The one name asked for (or the only one), else an error listing the names.

    Examples
    --------
    >>> pick(Path("a.npz"), ["x"], None, "array", "key=NAME")
    'x'
    """
    listed = ", ".join(repr(n) for n in names) or "none"
    if key is None:
        if len(names) == 1:
            return names[0]
        raise RadarConfigError(f"{path} holds {len(names)} {kind}s ({listed}); name the one to "
                               f"read ({how})")
    if key not in names:
        raise RadarConfigError(f"{path} has no {kind} {key!r}; its {kind}s are {listed}")
    return key
