"""Deterministic bytes for artifacts: canonical JSON, SHA-256, a reproducible ``.npz``,
checked reads (atomic writes: :mod:`backends.atomic`, re-exported here).

Nothing here knows about networks; :mod:`backends.artifact` builds the format on top.
Every writer is a pure function of its input (sorted keys, fixed zip dates and
attributes, no compression), so equal inputs give equal bytes and equal digests.
Every reader is bounded before it allocates: a file by its size
(:data:`MAX_MANIFEST_BYTES`, :data:`MAX_ARRAYS_BYTES`), an ``.npz`` member by the size
its zip entry and its ``.npy`` header declare (:func:`read_npz`, from
:mod:`backends.npz_reader`).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from backends.atomic import write_atomic
from backends.npz_reader import MAX_ARRAYS_BYTES, read_npz
from ir.errors import ArtifactError

__all__ = [
    "ARRAYS_FILE",
    "ARTIFACT_ENTRIES",
    "saved_entries",
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

#: The files at the top of an artifact directory of either kind (network: the two files
#: above; program: ``program.json``, ``report.md``, and ``networks/<k>/`` networks).
ARTIFACT_ENTRIES = frozenset({MANIFEST_FILE, ARRAYS_FILE, "program.json", "report.md"})
#: Largest manifest (``manifest.json``, ``program.json``) read: 64 MiB.
MAX_MANIFEST_BYTES = 64 << 20
#: Most bytes one read of an artifact file asks for past the size the file reports.
_PIECE_BYTES = 1 << 20
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # the earliest date a zip entry can hold


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


def _network_refs(folder: Path) -> list[str]:
    """The ``networks/<k>`` folders the ``program.json`` of ``folder`` refers to (none if it
    cannot be read)."""
    try:
        body = json.loads(read_bytes(folder / "program.json"))
        refs = [seg["network"]["path"] for seg in body["segments"] if seg["kind"] == "spiking"]
    except (ArtifactError, ValueError, TypeError, KeyError, RecursionError):
        return []
    return [r for r in refs if isinstance(r, str) and r.startswith("networks/")
            and r[len("networks/"):].isdecimal() and r[len("networks/"):].isascii()]


def saved_entries(folder: Path) -> set[str]:
    """What a save wrote into the artifact directory ``folder``: all that replacing it deletes.

    The top files of either kind (and the ``NAME.tmp`` an older radarsnn left beside
    them) and, for a program, each ``networks/<k>/`` its ``program.json`` refers to
    with that network's two files.  Anything else (a user's file, even
    ``networks/README.txt`` or ``networks/0/calib.npy``) is not the artifact's.

    Examples
    --------
    >>> sorted(saved_entries(Path("/nonexistent")))  # doctest: +NORMALIZE_WHITESPACE
    ['arrays.npz', 'arrays.npz.tmp', 'manifest.json', 'manifest.json.tmp', 'program.json',
     'program.json.tmp', 'report.md', 'report.md.tmp']
    """
    entries = set(ARTIFACT_ENTRIES)
    for ref in _network_refs(Path(folder)):
        entries |= {"networks", ref, f"{ref}/{MANIFEST_FILE}", f"{ref}/{ARRAYS_FILE}"}
    return entries | {f"{e}.tmp" for e in entries if "." in e.rsplit("/", 1)[-1]}


def read_bytes(path: Path, *, limit: int = MAX_MANIFEST_BYTES) -> bytes:
    """The bytes of an artifact file of at most ``limit`` bytes.

    Parameters
    ----------
    path : Path
    limit : int
        Largest size read; the size is checked before anything is read (a sparse
        20 GB file is refused, not loaded), and what the file holds is read in pieces of
        at most its size or 1 MiB, never more than ``limit + 1`` bytes in all (a file that
        grows, or reports size 0 like ``/proc`` files): a small file costs its own size
        whatever ``limit`` is.

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
            data = _read_at_most(f, size, limit) if size <= limit else b""
        if size > limit or len(data) > limit:
            raise ArtifactError(f"{path}: {max(size, len(data))} bytes, over the limit of {limit} "
                                "bytes for this file; not an artifact radarsnn wrote (or one too "
                                "large to load: re-compile smaller or split the chain)")
        return data
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        raise ArtifactError(f"{path}: cannot read ({getattr(exc, 'strerror', None) or exc}); is "
                            "this an artifact directory written by backends.artifact.save?"
                            ) from exc


def _read_at_most(f, size: int, limit: int) -> bytes:
    """What ``f`` holds, up to ``limit + 1`` bytes: first its ``size`` bytes, then 1 MiB pieces.

    ``f.read(n)`` reserves ``n`` bytes before reading, so ``n`` is never more than the
    file's size or one piece (``f.read(limit + 1)`` reserved 4 GiB for any ``arrays.npz``).
    """
    parts, total = [], 0
    while total <= limit:
        part = f.read(min(max(size - total, _PIECE_BYTES), limit + 1 - total))
        if not part:
            break
        parts.append(part)
        total += len(part)
    return b"".join(parts)  # one part (the usual case) is returned as is, not copied
