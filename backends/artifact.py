r"""Versioned, tamper-evident storage of a :class:`~compiler.snn.SpikingNetwork` on disk.

An artifact is a directory with two files:

``manifest.json``
    Everything but the large arrays, as strict JSON (no ``NaN`` tokens) written
    with ``json.dumps(sort_keys=True, indent=2, ensure_ascii=True)``: the format
    name and version, the radarsnn version, the network's name, ``n_steps`` and
    ``meta``, every population, projection, encoder and decoder, the caller's
    ``extra``, and two SHA-256 digests (see below).
``arrays.npz``
    Every array of every projection as a ``.npy`` member of an uncompressed zip
    with a fixed member date (1980-01-01), so equal networks give equal bytes.
    The manifest refers to each array as ``{"file": "arrays.npz", "key": k,
    "dtype": "<f8", "shape": [...]}``.

Integrity:

.. math::

    h_{arrays} = \mathrm{SHA256}(\text{arrays.npz bytes}), \qquad
    h_{manifest} = \mathrm{SHA256}(\mathrm{canonical}(M \setminus
    \{\text{manifest\_sha256}\}))

where ``canonical`` is ``json.dumps(sort_keys=True, separators=(",", ":"),
ensure_ascii=True)`` in UTF-8 and ``h_arrays`` is part of ``M``.  :func:`load`
also requires ``manifest.json`` to be byte-for-byte in its rendered form, so
*every* change to either file is refused with :class:`~ir.errors.ArtifactError`.

Versions are ``MAJOR.MINOR``: a reader accepts any minor of its own major (a
minor may only add top-level manifest keys, which older readers ignore) and
refuses a newer major with a message that says to upgrade.  Loading never runs
code: JSON through :mod:`json`, arrays with ``allow_pickle=False``, projection
classes only from an explicit registry (:data:`PROJECTION_KINDS`).

Examples
--------
>>> import tempfile
>>> from compiler.snn.examples import tiny_network
>>> net = tiny_network()  # two inputs, one neuron
>>> with tempfile.TemporaryDirectory() as tmp:
...     folder = save(net, tmp, extra={"note": "demo"})
...     back = load(folder)
...     sorted(p.name for p in folder.iterdir()), read_manifest(folder)["extra"]
(['arrays.npz', 'manifest.json'], {'note': 'demo'})
>>> back.name, back.n_steps, back.projections[0].weights.tolist()
('tiny', 8, [[1.0], [1.0]])
"""

from __future__ import annotations

import operator
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

import numpy as np
from pydantic import ValidationError

from backends.arguments import directory_arg, instance_arg
from backends.artifact_codec import network_from_manifest, population_entry, projection_entry
from backends.artifact_io import (
    ARRAYS_FILE,
    MANIFEST_FILE,
    MAX_ARRAYS_BYTES,
    finite_json,
    npz_bytes,
    plain_json,
    read_bytes,
    read_npz,
    render_json,
    saved_entries,
    sha256_hex,
)
from backends.atomic import replace_directory, write_file
from backends.manifest import radarsnn_version, read_manifest_file, seal
from compiler.snn import (
    MatrixProjection,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import ArtifactError, NetworkError
from ir.model import short_repr

__all__ = [
    "ARTIFACT_FORMAT",
    "ARTIFACT_VERSION",
    "PROJECTION_KINDS",
    "load",
    "network_files",
    "read_manifest",
    "save",
    "write_files",
]

#: Format name written into every manifest.
ARTIFACT_FORMAT = "radarsnn.spiking-network"
#: Format version ``MAJOR.MINOR`` this module writes (and the major it reads).
ARTIFACT_VERSION = "1.0"
#: Projection classes by their ``kind``: the only classes :func:`load` instantiates.
PROJECTION_KINDS: Mapping[str, type] = MappingProxyType(
    {"matrix": MatrixProjection, "stencil": StencilProjection}
)

def network_files(network: SpikingNetwork, *, extra: Mapping | None = None,
                  kinds: Mapping[str, type] = PROJECTION_KINDS) -> tuple[dict, dict[str, bytes]]:
    """The manifest and the bytes of both files of ``network``'s artifact (nothing written).

    Parameters
    ----------
    network, extra, kinds
        As for :func:`save`.

    Returns
    -------
    manifest : dict
        The sealed manifest (its ``manifest_sha256`` identifies the artifact).
    files : dict of str to bytes
        ``{"arrays.npz": ..., "manifest.json": ...}``.

    Raises
    ------
    NetworkError, ArtifactError
        As for :func:`save` (before any file is touched).
    """
    network.validate()
    arrays: dict[str, np.ndarray] = {}
    projections = []
    for index, proj in enumerate(network.projections):
        if kinds.get(proj.kind) is not type(proj):
            raise ArtifactError(f"projection {proj.id!r}: kind {proj.kind!r} "
                                f"({type(proj).__name__}) is not in the registry {sorted(kinds)}",
                                node=proj.id)
        projections.append(projection_entry(index, proj, arrays))
    npz = npz_bytes(arrays)
    body = {
        "format": ARTIFACT_FORMAT,
        "format_version": ARTIFACT_VERSION,
        "radarsnn_version": radarsnn_version(),
        "network": {"name": plain_json(network.name, "network name"),
                    "n_steps": operator.index(network.n_steps),
                    "meta": plain_json(network.meta, "network meta")},
        "populations": [population_entry(p) for p in network.populations],
        "projections": projections,
        "encoders": [finite_json(e.model_dump(mode="json")) for e in network.encoders],
        "decoders": [finite_json(d.model_dump(mode="json")) for d in network.decoders],
        "extra": plain_json(dict(extra or {}), "extra"),
        "arrays": {"file": ARRAYS_FILE, "sha256": sha256_hex(npz), "n_bytes": len(npz)},
    }
    manifest = seal(body)
    return manifest, {ARRAYS_FILE: npz, MANIFEST_FILE: render_json(manifest)}


def save(network: SpikingNetwork, directory: str | Path, *, extra: Mapping | None = None,
         kinds: Mapping[str, type] = PROJECTION_KINDS) -> Path:
    """Write ``network`` as an artifact directory, atomically (created, or replaced as a whole).

    Parameters
    ----------
    network : SpikingNetwork
        A network that passes :meth:`~compiler.snn.SpikingNetwork.validate`.
    directory : str or Path
        The artifact directory: new, empty, or an artifact (of either kind) to
        replace.  It then holds exactly ``manifest.json`` and ``arrays.npz``.
    extra : mapping, optional
        Caller's JSON data stored under the manifest key ``extra`` (read it back
        with :func:`read_manifest`).
    kinds : mapping of str to type
        The projection registry; every projection's ``kind`` must be in it.

    Returns
    -------
    Path
        ``directory``.

    Raises
    ------
    NetworkError
        If ``network`` does not validate.
    ArtifactError
        If ``meta``/``extra`` is not plain JSON, a projection kind is unknown, the
        directory holds files that are not an artifact's, or a file cannot be
        written (the directory is then unchanged).

    Notes
    -----
    Equal networks give byte-identical files (fixed key order, fixed zip dates,
    no compression), so artifacts can be compared and cached by hash.  The files
    are written into a hidden sibling directory, synced, and swapped into place
    in one rename (:func:`backends.atomic.replace_directory`): a crash or a full
    disk leaves the previous artifact or the new one, never a mixture.

    Examples
    --------
    >>> import tempfile
    >>> from compiler.snn import Encoder, Population, RateCode, SpikingNetwork
    >>> net = SpikingNetwork(name="src", n_steps=4,
    ...     populations=[Population(id="in", shape={"i": 3}, source=True)],
    ...     encoders=[Encoder(port="x", population="in", code=RateCode())])
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     save(net, tmp).joinpath("manifest.json").is_file()
    True
    """
    instance_arg(network, SpikingNetwork, "save", "network",
                 "save a CompiledProgram with backends.save (radarsnn.save)")
    folder = directory_arg(directory, "save")
    _, files = network_files(network, extra=extra, kinds=kinds)
    try:
        replace_directory(folder, lambda tmp: write_files(tmp, files), owned=saved_entries)
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        raise ArtifactError(f"cannot write the artifact to {folder}: {exc}") from exc
    return folder


def write_files(folder: Path, files: Mapping[str, bytes]) -> None:
    """Create each of ``files`` in the existing ``folder`` (synced by ``replace_directory``)."""
    for name, data in files.items():
        write_file(folder / name, data, sync=False)


def read_manifest(directory: str | Path) -> dict:
    """The checked manifest of an artifact (format, version, canonical form and digest).

    Parameters
    ----------
    directory : str or Path
        An artifact directory.

    Returns
    -------
    dict
        The parsed ``manifest.json`` (``extra`` holds what :func:`save` was given).

    Raises
    ------
    ArtifactError
        If the manifest is missing, unreadable, not JSON, of another format, of a
        newer major version, not in canonical form or not matching its digest.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     read_manifest(tmp)  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    ir.errors.ArtifactError: .../manifest.json: cannot read (No such file or directory); ...
    """
    return read_manifest_file(Path(directory) / MANIFEST_FILE, fmt=ARTIFACT_FORMAT,
                              current=ARTIFACT_VERSION,
                              what="radarsnn spiking-network artifact",
                              redo="re-emit the artifact")


def _read_arrays(path: Path, manifest: dict) -> dict[str, np.ndarray]:
    spec = manifest.get("arrays")
    if not isinstance(spec, dict) or spec.get("file") != ARRAYS_FILE:
        raise ArtifactError(f"{path.with_name(MANIFEST_FILE)}: the 'arrays' entry must name "
                            f"{ARRAYS_FILE!r}, got {short_repr(spec)}")
    raw = read_bytes(path, limit=MAX_ARRAYS_BYTES)
    digest = sha256_hex(raw)
    if digest != spec.get("sha256") or len(raw) != spec.get("n_bytes"):
        raise ArtifactError(f"{path}: {len(raw)} bytes with SHA-256 {digest}, but the manifest "
                            f"declares {spec.get('n_bytes')} bytes with {spec.get('sha256')}; "
                            "the file is truncated or was modified: re-emit the artifact")
    return read_npz(raw, path)



def load(directory: str | Path, *, kinds: Mapping[str, type] = PROJECTION_KINDS
         ) -> SpikingNetwork:
    """Read and check an artifact written by :func:`save`; return the validated network.

    Parameters
    ----------
    directory : str or Path
        The artifact directory.
    kinds : mapping of str to type
        The projection registry; the only classes instantiated.

    Returns
    -------
    SpikingNetwork
        Equal to the saved one field by field (arrays bit for bit, axis order kept).

    Raises
    ------
    ArtifactError
        For anything wrong: a missing or unreadable file, bad JSON, another format
        or a newer major version, a digest mismatch (truncation, flipped bytes,
        edits), a missing/extra array or one of the wrong dtype or shape, fields
        that do not parse, or a rebuilt network that fails ``validate()``.  The
        message names the file (and the entry) and what is wrong.

    Notes
    -----
    Checks run in this order: manifest readable → JSON object → format name →
    version → canonical form → manifest digest → npz size and digest → npz
    members → per-array dtype/shape → field parsing → ``validate()``.

    Examples
    --------
    >>> import tempfile
    >>> from compiler.snn import Encoder, Population, RateCode, SpikingNetwork
    >>> net = SpikingNetwork(name="src", n_steps=4,
    ...     populations=[Population(id="in", shape={"z": 2, "a": 3}, source=True)],
    ...     encoders=[Encoder(port="x", population="in", code=RateCode())])
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     load(save(net, tmp)).populations[0].axes
    ('z', 'a')
    """
    folder = directory_arg(directory, "load")
    manifest = read_manifest(folder)
    arrays = _read_arrays(folder / ARRAYS_FILE, manifest)
    path = folder / MANIFEST_FILE
    try:
        return network_from_manifest(manifest, arrays, kinds, path).validate()
    except ValidationError as exc:
        errors = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']} "
                           f"(got {short_repr(e['input'])})" for e in exc.errors())
        raise ArtifactError(f"{path}: a {exc.title} entry does not parse: {errors}") from exc
    except NetworkError as exc:
        raise ArtifactError(f"{path}: the stored network is invalid: {exc}", node=exc.node) from exc
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ArtifactError(f"{path}: malformed entry ({type(exc).__name__}: {exc})") from exc
