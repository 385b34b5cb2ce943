"""Deterministic bytes for artifacts: canonical JSON, SHA-256, a reproducible ``.npz``,
checked reads (atomic writes: :mod:`backends.atomic`, re-exported here).

Nothing here knows about networks; :mod:`backends.artifact` builds the format on top.
Every writer is a pure function of its input (sorted keys, fixed zip dates and
attributes, no compression), so equal inputs give equal bytes and equal digests.
Every reader is bounded before it allocates: a file by its size
(:data:`MAX_MANIFEST_BYTES`, :data:`MAX_ARRAYS_BYTES`), an ``.npz`` member by the size
its zip entry and its ``.npy`` header declare.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import tokenize
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from backends.atomic import write_atomic
from ir.errors import ArtifactError
from ir.model import short_repr

__all__ = [
    "ARRAYS_FILE",
    "ARTIFACT_ENTRIES",
    "MANIFEST_FILE",
    "MAX_ARRAYS_BYTES",
    "MAX_MANIFEST_BYTES",
    "canonical_json",
    "finite_json",
    "npz_bytes",
    "plain_json",
    "read_bytes",
    "read_npz",
    "render_json",
    "sha256_hex",
    "write_atomic",
]

#: The two files of an artifact directory (see :mod:`backends.artifact`).
MANIFEST_FILE = "manifest.json"
ARRAYS_FILE = "arrays.npz"

#: Every entry an artifact directory of either kind holds (network: the two files above;
#: program: ``program.json``, ``report.md``, ``networks/``); saving replaces only these.
ARTIFACT_ENTRIES = frozenset({MANIFEST_FILE, ARRAYS_FILE, "program.json", "report.md",
                              "networks"})
#: Largest manifest (``manifest.json``, ``program.json``) read: 64 MiB.
MAX_MANIFEST_BYTES = 64 << 20
#: Largest ``arrays.npz`` read, and the most its members may declare: 4 GiB (half the
#: simulator's default memory limit; the compiler's memory guard keeps the weights it writes
#: well below).
MAX_ARRAYS_BYTES = 4 << 30

_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # the earliest date a zip entry can hold
# what zipfile, zlib and numpy's header parser raise on damaged bytes
_DAMAGE = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, NotImplementedError,
           RuntimeError, ValueError, OSError, EOFError, KeyError, SyntaxError,
           tokenize.TokenError, TypeError, OverflowError)


def sha256_hex(data: bytes) -> str:
    """SHA-256 digest of ``data`` as 64 lowercase hex digits.

    Parameters
    ----------
    data : bytes

    Returns
    -------
    str

    Examples
    --------
    >>> sha256_hex(b"")[:16]
    'e3b0c44298fc1c14'
    """
    return hashlib.sha256(data).hexdigest()


def canonical_json(body: Mapping) -> bytes:
    """The hashed form: ``json.dumps(sort_keys=True, separators=(",", ":"), ensure_ascii=True)``.

    Parameters
    ----------
    body : mapping
        Strict JSON data (no NaN/inf).

    Returns
    -------
    bytes
        UTF-8 (pure ASCII) text.

    Raises
    ------
    ValueError
        For non-finite floats (``allow_nan=False``).

    Examples
    --------
    >>> canonical_json({"b": 1, "a": [1.5, None]})
    b'{"a":[1.5,null],"b":1}'
    """
    return json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      allow_nan=False).encode()


def render_json(manifest: Mapping) -> bytes:
    """The on-disk form: sorted keys, two-space indent, ASCII, a final newline.

    Parameters
    ----------
    manifest : mapping
        Strict JSON data (no NaN/inf).

    Returns
    -------
    bytes

    Raises
    ------
    ValueError
        For non-finite floats (``allow_nan=False``).

    Examples
    --------
    >>> render_json({"b": 1, "a": 2})
    b'{\\n  "a": 2,\\n  "b": 1\\n}\\n'
    """
    return (json.dumps(manifest, sort_keys=True, indent=2, ensure_ascii=True, allow_nan=False)
            + "\n").encode()


def finite_json(obj: Any) -> Any:
    """Non-finite floats as the strings pydantic parses back (``"NaN"``, ``"±Infinity"``).

    Parameters
    ----------
    obj : JSON-like
        Nested dicts, lists/tuples and scalars (tuples become lists).

    Returns
    -------
    JSON-like
        ``obj`` with every non-finite float replaced, so it is strict JSON.

    Examples
    --------
    >>> finite_json({"x": [float("nan"), -float("inf"), 1.0]})
    {'x': ['NaN', '-Infinity', 1.0]}
    """
    if isinstance(obj, float) and not math.isfinite(obj):
        return "NaN" if math.isnan(obj) else ("Infinity" if obj > 0 else "-Infinity")
    if isinstance(obj, dict):
        return {k: finite_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite_json(v) for v in obj]
    return obj


def plain_json(obj: Any, what: str) -> Any:
    """``obj`` if it survives a strict JSON round trip unchanged.

    Parameters
    ----------
    obj : object
        Caller data to store.
    what : str
        What ``obj`` is, for the error message (e.g. ``"network meta"``).

    Returns
    -------
    object
        ``obj`` itself.

    Raises
    ------
    ArtifactError
        If ``obj`` is not serialisable or changes on the round trip (int keys,
        tuples, NaN, ...).

    Examples
    --------
    >>> plain_json({"a": [1, 2.5]}, "extra")
    {'a': [1, 2.5]}
    >>> plain_json({1: "x"}, "extra")  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    ir.errors.ArtifactError: extra cannot be stored: it changes on a JSON round trip; ...
    """
    try:
        same = json.loads(json.dumps(obj, allow_nan=False, sort_keys=True)) == obj
    except (TypeError, ValueError) as exc:
        same, why = False, str(exc)
    else:
        why = "it changes on a JSON round trip"
    if not same:
        raise ArtifactError(f"{what} cannot be stored: {why}; use only dicts with str keys, lists, "
                            "str, int, bool, None and finite floats")
    return obj


def npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """A deterministic ``.npz``: stored members, fixed dates and attributes, keys in order.

    Parameters
    ----------
    arrays : mapping of str to ndarray
        Member name (without ``.npy``) -> array; no object arrays.

    Returns
    -------
    bytes
        An uncompressed zip readable by ``np.load``; equal input gives equal bytes.

    Examples
    --------
    >>> a = {"w": np.arange(3)}
    >>> npz_bytes(a) == npz_bytes(a), read_npz(npz_bytes(a), Path("x.npz"))["w"].tolist()
    (True, [0, 1, 2])
    """
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as zf:
        for key, array in arrays.items():
            npy = io.BytesIO()
            np.lib.format.write_array(npy, array, allow_pickle=False)
            info = zipfile.ZipInfo(f"{key}.npy", date_time=_ZIP_DATE)
            info.create_system, info.external_attr = 3, 0o644 << 16
            zf.writestr(info, npy.getvalue())
    return buffer.getvalue()


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
        ``limit`` bytes, an object dtype, or a header whose shape and dtype do not
        account exactly for the member's bytes (so a forged ``(10**12,)`` header is
        refused before numpy allocates 7 TiB).

    Examples
    --------
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


def read_bytes(path: Path, *, limit: int = MAX_MANIFEST_BYTES) -> bytes:
    """The bytes of an artifact file of at most ``limit`` bytes.

    Parameters
    ----------
    path : Path
    limit : int
        Largest size read; the size is checked before anything is read (a sparse
        20 GB file is refused, not loaded), and at most ``limit + 1`` bytes are read
        (a file that grows, or reports size 0 like ``/proc`` files).

    Returns
    -------
    bytes

    Raises
    ------
    ArtifactError
        If the file is missing, unreadable, not a regular file, or over ``limit``.

    Examples
    --------
    >>> read_bytes(Path("/nonexistent/manifest.json"))  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    ir.errors.ArtifactError: /nonexistent/manifest.json: cannot read (...); ...
    """
    try:
        if path.exists() and not path.is_file():  # a directory, a device (/dev/zero: forever)
            raise ArtifactError(f"{path}: cannot read (not a regular file); is this an artifact "
                                "directory written by backends.artifact.save?")
        with path.open("rb") as f:
            size = os.fstat(f.fileno()).st_size
            data = f.read(limit + 1) if size <= limit else b""
        if size > limit or len(data) > limit:
            raise ArtifactError(f"{path}: {max(size, len(data))} bytes, over the limit of {limit} "
                                "bytes for this file; not an artifact radarsnn wrote (or one too "
                                "large to load: re-compile smaller or split the chain)")
        return data
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        raise ArtifactError(f"{path}: cannot read ({getattr(exc, 'strerror', None) or exc}); is "
                            "this an artifact directory written by backends.artifact.save?"
                            ) from exc
