"""Checked manifests: the JSON file that names, versions and seals an artifact.

Both artifact kinds — one spiking network (:mod:`backends.artifact`,
``manifest.json``) and a whole compiled program
(:mod:`backends.program_artifact`, ``program.json``) — start with a manifest
carrying ``format``, ``format_version`` (``MAJOR.MINOR``), the writing
``radarsnn_version`` and ``manifest_sha256``, the SHA-256 of the canonical JSON
of every other field.  :func:`read_manifest_file` is the one reader: it
refuses anything that is not exactly what the writer produced.
"""

from __future__ import annotations

import json
import re
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from backends.artifact_io import (
    MAX_MANIFEST_BYTES,
    canonical_json,
    read_bytes,
    render_json,
    sha256_hex,
)
from ir.errors import ArtifactError
from ir.model import short_repr
from ir.parsing import load_json

__all__ = ["HASH_KEY", "radarsnn_version", "read_manifest_file", "seal"]

#: The manifest field holding the digest of the others.
HASH_KEY = "manifest_sha256"

_VERSION = re.compile(r"[0-9]{1,9}\.[0-9]{1,9}")


def radarsnn_version() -> str:
    """The installed radarsnn's version (``0+unknown`` when run from a bare checkout)."""
    try:
        return version("radarsnn")
    except PackageNotFoundError:
        return "0+unknown"


def seal(body: dict) -> dict:
    """``body`` with its digest under :data:`HASH_KEY`.

    Examples
    --------
    >>> seal({"format": "x"})[HASH_KEY][:12]
    '368ff2611c92'
    """
    return {**body, HASH_KEY: sha256_hex(canonical_json(body))}


def read_manifest_file(path: Path, *, fmt: str, current: str, what: str, redo: str) -> dict:
    """Read and check one manifest file.

    Parameters
    ----------
    path : Path
        The manifest file.
    fmt : str
        The expected ``format``.
    current : str
        The format version this radarsnn writes (``MAJOR.MINOR``); files of the
        same major version are read.
    what : str
        What the format is, for messages (e.g. ``"radarsnn spiking-network artifact"``).
    redo : str
        How to get a good file again (e.g. ``"re-emit the artifact"``).

    Returns
    -------
    dict
        The parsed manifest.

    Raises
    ------
    ArtifactError
        If the file is missing, unreadable, not UTF-8 JSON, not an object, of another
        format, of another major version, not in the writer's canonical form, or not
        matching its digest — each naming the file and what to do.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = Path(tmp) / "m.json"
    ...     _ = path.write_bytes(render_json(seal({"format": "x", "format_version": "1.0"})))
    ...     read_manifest_file(path, fmt="x", current="1.2", what="x file", redo="redo")["format"]
    'x'
    """
    raw = read_bytes(path, limit=MAX_MANIFEST_BYTES)
    try:  # bounded nesting (ir.parsing): a forged manifest of 5 000 '[' is not a RecursionError
        manifest = load_json(raw.decode("utf-8"), error=ArtifactError)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ArtifactError(f"{path}: not valid UTF-8 JSON ({exc})") from exc
    except ArtifactError as exc:
        raise ArtifactError(f"{path}: {exc}") from exc
    if not isinstance(manifest, dict):
        raise ArtifactError(f"{path}: the top level is a {type(manifest).__name__}, not an object")
    found = manifest.get("format")
    if found != fmt:
        raise ArtifactError(f"{path}: format is {short_repr(found)}, expected {fmt!r}; not a "
                            f"{what}")
    text = manifest.get("format_version")
    # ASCII digits only: str.isdigit() accepts '²' and int() then fails; at most 9 of them
    if not (isinstance(text, str) and _VERSION.fullmatch(text)):
        raise ArtifactError(f"{path}: format_version {short_repr(text)} is not MAJOR.MINOR "
                            "(digits 0-9)")
    major, ours = int(text.split(".")[0]), int(current.split(".")[0])
    if major > ours:
        raise ArtifactError(
            f"{path}: written by radarsnn {manifest.get('radarsnn_version')}, format {text}; "
            f"this radarsnn ({radarsnn_version()}) reads {ours}.x: upgrade radarsnn")
    if major < ours:
        raise ArtifactError(f"{path}: format {text} is older than {ours}.x and cannot be read; "
                            f"{redo} with this radarsnn")
    try:
        canonical = render_json(manifest) == raw
    except ValueError:  # NaN/Infinity tokens: not strict JSON
        canonical = False
    if not canonical:
        raise ArtifactError(f"{path}: not in the canonical form radarsnn writes (edited by "
                            f"hand?); {redo}")
    body = {k: v for k, v in manifest.items() if k != HASH_KEY}
    digest = sha256_hex(canonical_json(body))
    if manifest.get(HASH_KEY) != digest:
        raise ArtifactError(f"{path}: content digest mismatch (stored {manifest.get(HASH_KEY)!r}, "
                            f"computed {digest!r}); the manifest was modified after it was "
                            f"written: {redo}")
    return manifest
