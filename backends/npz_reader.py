"""Reading an artifact's ``.npz`` without trusting it: every member checked before numpy
allocates anything.

A zip member's declared size and its ``.npy`` header (shape and dtype) are read and checked
against the member's bytes and :data:`MAX_ARRAYS_BYTES` first, so a forged header declaring
``(10**12,)`` is refused instead of numpy allocating 7 TiB.  Members must be stored
uncompressed, as :func:`backends.artifact_io.npz_bytes` writes them: the file's size then
bounds what is read, where a 4 MB deflated member could inflate to 4 GiB.  Damaged zips
are :class:`~ir.errors.ArtifactError` like any other damage.  Arrays are read with
``allow_pickle=False``.
"""

from __future__ import annotations

import io
import tokenize
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ir.errors import ArtifactError
from ir.model import short_repr

__all__ = ["MAX_ARRAYS_BYTES", "read_npz"]

#: Largest ``arrays.npz`` read, and the most its members may declare: 4 GiB (half the
#: simulator's default memory limit; the compiler's memory guard keeps the weights it writes
#: well below).
MAX_ARRAYS_BYTES = 4 << 30

# what zipfile, zlib and numpy's header parser raise on damaged bytes
_DAMAGE = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, NotImplementedError,
           RuntimeError, ValueError, OSError, EOFError, KeyError, SyntaxError,
           tokenize.TokenError, TypeError, OverflowError)


def read_npz(raw: bytes, path: Path, *, limit: int = MAX_ARRAYS_BYTES
             ) -> dict[str, np.ndarray]:
    """Every member of an in-memory ``.npz``, without pickle, each checked before it is read.

    Parameters
    ----------
    raw : bytes
        The file's bytes.
    path : Path
        Where they came from (for messages).
    limit : int
        Most bytes the members may hold uncompressed, together.

    Returns
    -------
    dict of str to ndarray

    Raises
    ------
    ArtifactError
        If ``raw`` is not a zip of plain ``.npy`` members: a damaged zip or deflate
        stream, a member not named ``*.npy`` or named twice, members declaring more than
        ``limit`` bytes, a compressed member (radarsnn stores them: a deflated one could
        inflate to gigabytes from a few MB), an object dtype, or a header whose shape and
        dtype do not account exactly for the member's bytes (so a forged ``(10**12,)``
        header is refused before numpy allocates 7 TiB).

    Examples
    --------
    >>> from backends.artifact_io import npz_bytes
    >>> read_npz(npz_bytes({"k": np.ones(2)}), Path("a.npz"))["k"].tolist()
    [1.0, 1.0]
    >>> read_npz(npz_bytes({"k": np.ones(2)}), Path("a.npz"), limit=100)
    Traceback (most recent call last):
    ...
    ir.errors.ArtifactError: a.npz: the members declare 144 bytes uncompressed, over the \
limit of 100 bytes; not an artifact radarsnn wrote (or one too large to load)
    """
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            infos = zf.infolist()
            declared = sum(info.file_size for info in infos)
            if declared > limit:
                raise ArtifactError(f"{path}: the members declare {declared} bytes uncompressed, "
                                    f"over the limit of {limit} bytes; not an artifact radarsnn "
                                    "wrote (or one too large to load)")
            arrays: dict[str, np.ndarray] = {}
            packed = [i.filename for i in infos if i.compress_type != zipfile.ZIP_STORED]
            if packed:
                raise ArtifactError(f"{path}: member {short_repr(packed[0])} is compressed; "
                                    "radarsnn stores every member uncompressed (a compressed "
                                    "one is refused unread: a few MB could inflate to "
                                    "gigabytes); re-emit the artifact")
            for info in infos:
                key = info.filename.removesuffix(".npy")
                if key == info.filename or key in arrays:
                    raise ArtifactError(f"{path}: member {info.filename!r} is "
                                        + ("not a .npy array" if key == info.filename
                                           else "repeated") + "; re-emit the artifact")
                arrays[key] = _npy_member(zf.read(info), f"{path}: member {info.filename!r}")
            return arrays
    except ArtifactError:
        raise
    except _DAMAGE as exc:
        raise ArtifactError(f"{path}: not a readable .npz of plain arrays "
                            f"({type(exc).__name__}: {exc})") from exc


def _npy_member(data: bytes, where: str) -> np.ndarray:
    """One ``.npy`` member's array, after its header is checked against its bytes."""
    fmt = np.lib.format
    f = io.BytesIO(data)
    version = fmt.read_magic(f)
    if version not in ((1, 0), (2, 0)):
        raise ArtifactError(f"{where}: .npy format version {version} is not one radarsnn "
                            "writes (1.0 or 2.0)")
    shape, _, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                       else fmt.read_array_header_2_0(f))
    if dtype.hasobject:
        raise ArtifactError(f"{where}: object arrays are refused (they load only with "
                            "allow_pickle, which runs code)")
    count = 1
    for n in shape:
        count *= n
    need, have = count * dtype.itemsize, len(data) - f.tell()
    if count < 0 or need != have:
        raise ArtifactError(f"{where}: the header declares shape {short_repr(shape)} of "
                            f"{dtype.str} ({need} bytes) but the member holds {have} bytes of "
                            "data; re-emit the artifact")
    f.seek(0)
    return fmt.read_array(f, allow_pickle=False)
