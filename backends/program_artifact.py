r"""A whole :class:`~compiler.program.CompiledProgram` on disk: its graph, segments and networks.

A program artifact is a directory::

    program.json          graph and report (as JSON text: their key order matters), segments,
                          options, target profile (strict JSON)
    report.md             the resource report for people (not read back)
    networks/0/ …         one spiking-network artifact per spiking segment (backends.artifact)

``program.json`` is written like a network manifest (sorted keys, ASCII, two-space
indent) with a SHA-256 of its canonical form and the ``manifest_sha256`` of every
network it refers to, so an edit to any file of the directory is refused on
:func:`load_program`.  Equal programs give byte-identical directories.  Loading
never runs code: JSON through :mod:`json`, the graph through
:meth:`ir.Graph.from_dict` (pydantic-validated ops), networks through
:func:`backends.artifact.load`.

Examples
--------
>>> import tempfile
>>> import numpy as np
>>> from compiler.compile import compile_graph
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 3}},
...     {"id": "m", "op": "magnitude", "input": "a", "kind": "square"},
...     {"id": "o", "op": "output", "input": "m"}]})
>>> with tempfile.TemporaryDirectory() as tmp:
...     back = load_program(save_program(compile_graph(g), tmp))
>>> [s.kind for s in back.segments], back.target.name, back.graph == g
(['host', 'host'], 'loihi2', True)
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping
from pathlib import Path

from backends.arguments import directory_arg, instance_arg
from backends.artifact import load, network_files, read_manifest, write_files
from backends.artifact_io import plain_json, render_json, saved_entries
from backends.atomic import replace_directory, write_file
from backends.manifest import HASH_KEY, radarsnn_version, read_manifest_file, seal
from backends.reference.program import check_program
from compiler.compile import calibrate_pass
from compiler.hardware import HardwareProfile
from compiler.program import CompiledProgram, Segment
from compiler.report import Report
from ir import Graph
from ir.errors import ArtifactError, RadarSNNError
from ir.model import short_repr
from ir.parsing import load_json

__all__ = ["PROGRAM_FILE", "PROGRAM_FORMAT", "PROGRAM_VERSION", "is_program", "load_program",
           "read_program_manifest", "save_program"]

log = logging.getLogger(__name__)

#: The program manifest's file name.
PROGRAM_FILE = "program.json"
#: Format name written into every program manifest.
PROGRAM_FORMAT = "radarsnn.program"
#: ``MAJOR.MINOR`` of the program format this module writes (and the major it reads).
PROGRAM_VERSION = "1.0"


def is_program(directory: str | Path) -> bool:
    """Whether ``directory`` holds a program artifact (rather than one network's).

    Examples
    --------
    >>> is_program("/nonexistent")
    False
    """
    try:
        return (Path(directory) / PROGRAM_FILE).is_file()
    except (OSError, ValueError):  # a name too long for the file system, a NUL byte
        return False


def _segment_entry(seg: Segment, digests: list[str]) -> dict:
    entry = {"kind": seg.kind, "inputs": list(seg.inputs), "outputs": list(seg.outputs)}
    if seg.kind == "spiking":
        entry["network"] = {"path": f"networks/{len(digests) - 1}",
                            "manifest_sha256": digests[-1]}
    else:
        entry["node"] = seg.node
    return entry


def save_program(program: CompiledProgram, directory: str | Path, *,
                 extra: Mapping | None = None) -> Path:
    """Write ``program`` as a program artifact directory, atomically (created or replaced).

    Parameters
    ----------
    program : CompiledProgram
        What :func:`compiler.compile.compile_graph` returned.
    directory : str or Path
        The artifact directory: new, empty, or an artifact (of either kind) to
        replace as a whole — ``program.json``, ``report.md`` and ``networks/``
        (no network folder of an earlier program is left behind).
    extra : mapping, optional
        Caller's JSON data stored under ``extra``.

    Returns
    -------
    Path
        ``directory``.

    Raises
    ------
    ArtifactError
        Options, report or ``extra`` that are not plain JSON, a directory holding
        files that are not an artifact's, or a file that cannot be written (the
        directory is then unchanged).

    Notes
    -----
    The tree is written into a hidden sibling directory, synced, and swapped into
    place in one rename (:func:`backends.atomic.replace_directory`): a crash or a
    full disk leaves the previous program or the new one, never a mixture.
    """
    instance_arg(program, CompiledProgram, "save_program", "program",
                 "save a SpikingNetwork with backends.save (radarsnn.save)")
    folder = directory_arg(directory, "save_program")
    try:
        replace_directory(folder, lambda tmp: _write_program(program, tmp, extra),
                          owned=saved_entries)
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        raise ArtifactError(f"cannot write the program artifact to {folder}: {exc}") from exc
    log.info("saved program %r (%d segment(s)) to %s", program.graph.name,
             len(program.segments), folder)
    return folder


def _write_program(program: CompiledProgram, folder: Path, extra: Mapping | None) -> None:
    """The files of ``program``'s artifact, into the empty ``folder``."""
    digests: list[str] = []
    segments = []
    for seg in program.segments:
        if seg.kind == "spiking":
            manifest, files = network_files(seg.network)
            net_dir = folder / "networks" / str(len(digests))
            net_dir.mkdir(parents=True)
            write_files(net_dir, files)
            digests.append(manifest[HASH_KEY])
        segments.append(_segment_entry(seg, digests))
    report = program.records.report
    target = program.target
    body = {
        "format": PROGRAM_FORMAT,
        "format_version": PROGRAM_VERSION,
        "radarsnn_version": radarsnn_version(),
        # as JSON text: the manifest's keys are sorted, and a tensor's axes are ordered
        "graph": json.dumps(plain_json(program.graph.to_dict(), "graph"), ensure_ascii=True),
        "segments": segments,
        "options": plain_json(_jsonable(program.options), "compile options"),
        "target": None if target is None else plain_json(target.model_dump(mode="json"),
                                                          "target profile"),
        "report": None if report is None else report.to_json(indent=None),
        "extra": plain_json(dict(extra or {}), "extra"),
    }
    write_file(folder / PROGRAM_FILE, render_json(seal(body)), sync=False)  # synced with the tree
    if report is not None:
        write_file(folder / "report.md", report.to_markdown().encode("utf-8"), sync=False)


def _jsonable(options: Mapping) -> dict:
    """Compile options with tuples as lists (JSON has no tuples)."""
    return json.loads(json.dumps(dict(options), default=list))


def _network_dir(folder: Path, ref: str, path: Path) -> Path:
    """``folder/ref`` if it is a real ``networks/<name>`` directory of this artifact.

    A symlink anywhere below ``folder`` (``networks/`` itself or the network's folder)
    could point outside the artifact, so it is refused, as is a path that leaves it.
    """
    networks = folder / "networks"
    try:
        net_dir = folder / str(ref)
        for part in (networks, net_dir):
            if part.is_symlink():
                raise ArtifactError(f"{path}: {part} is a symbolic link; a program artifact's "
                                    "networks/ must be real folders inside it (re-save the "
                                    "program)")
        inside = (net_dir.resolve().parent == networks.resolve()
                  and networks.resolve().is_relative_to(folder.resolve()))
    except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL byte
        raise ArtifactError(f"{path}: network path {short_repr(ref)} cannot be used "
                            f"({getattr(exc, 'strerror', None) or exc})") from exc
    if not inside:
        raise ArtifactError(f"{path}: network path {short_repr(ref)} leaves the artifact's "
                            "networks/ folder")
    return net_dir


def _json_field(manifest: dict, key: str, path: Path) -> object:
    """A field of ``program.json`` that holds JSON text, parsed within :mod:`ir.parsing`'s
    bounds (nesting depth)."""
    text = manifest[key]
    if not isinstance(text, str):
        raise ArtifactError(f"{path}: field {key!r} must hold JSON text; got "
                            f"{type(text).__name__}")
    try:
        return load_json(text, error=ArtifactError)
    except json.JSONDecodeError as exc:
        raise ArtifactError(f"{path}: field {key!r} is not valid JSON ({exc})") from exc
    except ArtifactError as exc:
        raise ArtifactError(f"{path}: field {key!r}: {exc}") from exc


def read_program_manifest(directory: str | Path) -> dict:
    """The checked ``program.json`` of a program artifact (format, version, canonical, digest)."""
    return read_manifest_file(Path(directory) / PROGRAM_FILE, fmt=PROGRAM_FORMAT,
                              current=PROGRAM_VERSION, what="radarsnn program artifact",
                              redo="re-compile the chain")


def load_program(directory: str | Path) -> CompiledProgram:
    """Read and check a program artifact written by :func:`save_program`.

    Returns
    -------
    CompiledProgram
        Graph, segments (networks loaded and validated), options, target, and
        ``records["report"]`` when the program had a report.

    Raises
    ------
    ArtifactError
        A missing, edited or truncated file, another format or major version,
        a network whose digest differs from the one recorded, or a graph or
        profile that does not parse (the message names the file).
    """

    folder = directory_arg(directory, "load_program")
    manifest = read_program_manifest(folder)
    path = folder / PROGRAM_FILE
    try:
        graph = Graph.from_dict(_json_field(manifest, "graph", path))
        graph.verify()
        segments = []
        for entry in manifest["segments"]:
            if entry["kind"] == "spiking":
                ref = entry["network"]
                net_dir = _network_dir(folder, ref["path"], path)
                if read_manifest(net_dir)[HASH_KEY] != ref["manifest_sha256"]:
                    raise ArtifactError(f"{net_dir}: not the network this program was saved "
                                        "with (digest differs); re-compile the chain")
                segments.append(Segment(kind="spiking", inputs=list(entry["inputs"]),
                                        outputs=list(entry["outputs"]), network=load(net_dir)))
            elif entry["kind"] == "host":
                segments.append(Segment(kind="host", inputs=list(entry["inputs"]),
                                        outputs=list(entry["outputs"]), node=str(entry["node"])))
            else:
                raise ArtifactError(f"{path}: unknown segment kind {entry['kind']!r}")
        target = manifest["target"]
        profile = None if target is None else HardwareProfile.model_validate(target)
        report = manifest["report"]
        records = {} if report is None else {"report": Report(_json_field(manifest, "report",
                                                                           path))}
        options = dict(manifest["options"])
        policy = calibrate_pass(options).policy  # the stored options, typed as compiled
        program = CompiledProgram(graph=graph, segments=segments, options=options,
                                  records=records, target=profile, calibration_policy=policy)
        check_program(program)
    except ArtifactError:
        raise
    except RadarSNNError as exc:
        raise ArtifactError(f"{path}: the stored program is invalid: {exc}", node=exc.node) from exc
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ArtifactError(f"{path}: malformed entry ({type(exc).__name__}: {exc})") from exc
    return program
