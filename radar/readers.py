"""Arrays in the files radar users have on disk: ``.npy`` files and ``.npz`` archives.

MATLAB ``.mat`` files are read by :mod:`radar.mat_reader`, raw TI captures (``.bin``) by
:mod:`radar.ti_capture`. Loading never runs code: arrays are read with
``allow_pickle=False`` after their header is checked (object dtypes refused; the shape
against ``max_bytes``, the port's ``frame_shape`` when given, and the bytes the file or
member holds), so a forged shape or a deflate bomb cannot make numpy allocate or inflate
more than the port could take. Only regular files are opened (a FIFO is refused, never
waited on). Every error is a :class:`ir.errors.RadarConfigError` naming the file.
"""

from __future__ import annotations

import tokenize
import zipfile
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ir.errors import RadarConfigError
from radar.files import MAX_ARRAY_BYTES, check_frame_shape, open_regular, pick, shape_text
from radar.mat_reader import MAT_NUMERIC_CLASSES, read_mat_array

__all__ = ["MAX_ARRAY_BYTES", "MAT_NUMERIC_CLASSES", "read_mat_array", "read_npy_array",
           "read_npz_array", "read_npz_arrays"]

_DAMAGE = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, NotImplementedError,
           RuntimeError, ValueError, OSError, EOFError, KeyError, SyntaxError, IndexError,
           tokenize.TokenError, TypeError, OverflowError, MemoryError)


def read_npz_array(path: str | Path, key: str | None = None, *,
                   max_bytes: int = MAX_ARRAY_BYTES,
                   frame_shape: Sequence[int] | None = None) -> np.ndarray:
    """One array of a ``.npz`` archive (``np.savez``, or ``radarsnn run -o``), without pickle.

    Parameters
    ----------
    path : str or Path
        The archive.
    key : str, optional
        The array's name; default: the archive's only array.
    max_bytes : int
        Most bytes the array may declare.
    frame_shape : sequence of int, optional
        One frame of the port the array is for: it must declare this shape or
        ``(frames, *frame_shape)`` (:func:`radar.files.check_frame_shape`), checked before
        the member is inflated.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    RadarConfigError
        The file is missing, not a regular file or not a readable zip of ``.npy`` members;
        ``key`` is not in it (or is omitted while it holds several arrays: the message lists
        them); the array is an object array, declares more than ``max_bytes`` or a shape
        the port does not take, or its header does not match the member's bytes. A member
        inflates to at most what its header declares (zipfile stops at the member's
        declared size; the header must account for exactly that size).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     np.savez(Path(tmp) / "out.npz", det=np.eye(2), rd=np.zeros(3))
    ...     det = read_npz_array(Path(tmp) / "out.npz", "det")
    ...     try:
    ...         read_npz_array(Path(tmp) / "out.npz")
    ...     except RadarConfigError as err:
    ...         message = str(err)
    >>> det.tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    >>> print(message.split("out.npz ", 1)[1])
    holds 2 arrays ('det', 'rd'); name the one to read (key=NAME; on the command line FILE.npz:NAME)
    """
    path = Path(path)
    try:
        with open_regular(path, str(path)) as raw, zipfile.ZipFile(raw) as zf:
            members = {i.filename.removesuffix(".npy"): i for i in zf.infolist()
                       if i.filename.endswith(".npy")}
            name = pick(path, list(members), key, "array", "key=NAME; on the command line "
                        "FILE.npz:NAME")
            return _member(zf, members[name], path, name, max_bytes, frame_shape)
    except RadarConfigError:
        raise
    except _DAMAGE as err:
        raise RadarConfigError(f"{path}: not a readable .npz archive of arrays "
                               f"({type(err).__name__}: {err}); write it with numpy.savez"
                               ) from None


def read_npz_arrays(path: str | Path, *, max_bytes: int = MAX_ARRAY_BYTES
                    ) -> dict[str, np.ndarray]:
    """Every array of a ``.npz`` archive, each checked as :func:`read_npz_array` checks one.

    Parameters
    ----------
    path : str or Path
    max_bytes : int
        Most bytes the arrays may declare together.

    Returns
    -------
    dict of str to ndarray
        By member name without ``.npy``, in the archive's order.

    Raises
    ------
    RadarConfigError
        As :func:`read_npz_array`; a member that is not a ``.npy`` array or is repeated;
        the arrays declaring more than ``max_bytes`` together.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     np.savez_compressed(Path(tmp) / "w.npz", a=np.ones(2), b=np.zeros((1, 3)))
    ...     arrays = read_npz_arrays(Path(tmp) / "w.npz")
    >>> {k: v.shape for k, v in arrays.items()}
    {'a': (2,), 'b': (1, 3)}
    """
    path = Path(path)
    try:
        with open_regular(path, str(path)) as raw, zipfile.ZipFile(raw) as zf:
            arrays: dict[str, np.ndarray] = {}
            left = max_bytes
            for info in zf.infolist():
                name = info.filename.removesuffix(".npy")
                if name == info.filename or name in arrays:
                    raise RadarConfigError(f"{path}: member {info.filename[:60]!r} is "
                                           + ("repeated" if name in arrays else
                                              "not a .npy array") + "; write it with numpy.savez")
                arrays[name] = _member(zf, info, path, name, left, None)
                left -= arrays[name].nbytes
            return arrays
    except RadarConfigError:
        raise
    except _DAMAGE as err:
        raise RadarConfigError(f"{path}: not a readable .npz archive of arrays "
                               f"({type(err).__name__}: {err}); write it with numpy.savez"
                               ) from None


def _member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path: Path, name: str,
            max_bytes: int, frame_shape: Sequence[int] | None) -> np.ndarray:
    """One member's array, its header checked first: it is inflated only if it declares
    at most ``max_bytes``, a shape the port takes and exactly the member's size."""
    fmt = np.lib.format
    with zf.open(info) as f:
        version = fmt.read_magic(f)
        shape, _, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                           else fmt.read_array_header_2_0(f))
        have = info.file_size - f.tell()
    if dtype.hasobject:
        raise RadarConfigError(f"{path}: array {name!r} is an object array, refused "
                               "(loading it would unpickle code); save numbers")
    need = int(np.prod(shape, dtype=object)) * dtype.itemsize
    if need > max_bytes:
        raise RadarConfigError(f"{path}: array {name!r} declares {shape_text(shape)} "
                               f"{dtype} ({need} bytes), over the limit of {max_bytes} "
                               "bytes; save fewer frames per file")
    check_frame_shape(f"{path}: array {name!r}", shape, frame_shape)
    if need != have:
        raise RadarConfigError(f"{path}: array {name!r} declares {shape_text(shape)} "
                               f"{dtype} ({need} bytes) but its member holds {have} bytes; "
                               "the file is damaged or truncated, write it again")
    with zf.open(info) as f:
        return fmt.read_array(f, allow_pickle=False)


def read_npy_array(path: str | Path, *, max_bytes: int = MAX_ARRAY_BYTES,
                   frame_shape: Sequence[int] | None = None, what: str | None = None
                   ) -> np.ndarray:
    """One array of a ``.npy`` file, its header checked before numpy allocates anything.

    Parameters
    ----------
    path : str or Path
    max_bytes : int
        Most bytes the array may declare.
    frame_shape : sequence of int, optional
        One frame of the port the array is for (as :func:`read_npz_array`).
    what : str, optional
        Names the file in messages (``"cannot read {what}: ..."``); default the path.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    RadarConfigError
        Missing, empty, truncated or damaged files, not a regular file (a FIFO is refused
        at once, never waited on), object arrays, a declared size over ``max_bytes`` or
        over what the file holds (a sparse file declaring 10¹² values included), a shape
        the port does not take, ``.npz`` archives.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     np.save(Path(tmp) / "x.npy", np.arange(6.0).reshape(2, 3))
    ...     x = read_npy_array(Path(tmp) / "x.npy", frame_shape=(3,))
    ...     try:
    ...         read_npy_array(Path(tmp) / "x.npy", frame_shape=(4,), what="x.npy")
    ...     except RadarConfigError as err:
    ...         message = str(err)
    >>> x.shape, message
    ((2, 3), "cannot read x.npy: declares shape (2, 3), but the port takes (4,) (one frame) \
or (frames, 4); give the port's shape (nothing was read)")
    """
    what = str(path) if what is None else what
    fmt = np.lib.format
    try:
        with open_regular(path, f"cannot read {what}") as f:
            if f.read(4) == b"PK\x03\x04":
                raise RadarConfigError(f"cannot read {what}: it is a .npz archive; name it "
                                       "X.npz and give it as X.npz or X.npz:KEY")
            f.seek(0)
            version = fmt.read_magic(f)
            shape, _, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                               else fmt.read_array_header_2_0(f))
            if dtype.hasobject:
                raise RadarConfigError(f"cannot read {what}: object arrays are refused (loading "
                                       "them would unpickle code); save a numeric array")
            need = int(np.prod(shape, dtype=object)) * dtype.itemsize
            here = f.tell()
            have = f.seek(0, 2) - here
            if need > max_bytes:
                raise RadarConfigError(f"cannot read {what}: the header declares "
                                       f"{shape_text(shape)} {dtype} ({need} bytes), over the "
                                       f"limit of {max_bytes} bytes; give fewer frames per file")
            check_frame_shape(f"cannot read {what}", shape, frame_shape)
            if have < need:
                raise RadarConfigError(f"cannot read {what}: the header declares "
                                       f"{shape_text(shape)} {dtype} ({need} bytes) but the file "
                                       f"holds {have}; truncated?")
            f.seek(0)  # read from the file checked, not from a path someone may have swapped
            return fmt.read_array(f, allow_pickle=False)
    except RadarConfigError:
        raise
    except _DAMAGE as err:
        raise RadarConfigError(f"cannot read {what}: {err or type(err).__name__}") from None
