"""A generated package on disk: written atomically, replacing only what an earlier emit wrote.

:func:`write_package` writes the package's files into a hidden sibling folder and swaps it
into place in one rename (:func:`backends.atomic.replace_directory`), so a process killed
at any moment leaves the previous package or the new one, never a partial one.
``names.json`` lists every file emit wrote (``files``); re-emitting replaces exactly those
(and the bytecode Python compiled from them, ``__pycache__/<module>.*.pyc``, which would
otherwise be stale).  Every other entry (a user's notes, inputs, sub-folders) is kept in
the new package, byte for byte; one that the new package would overwrite is refused.

Examples
--------
>>> import tempfile
>>> with tempfile.TemporaryDirectory() as tmp:
...     names = dict.fromkeys(("package", "chain", "target", "radarsnn_version", "stages"))
...     pkg = write_package(Path(tmp) / "p", {"a.py": b"x = 1\\n"}, names)
...     _ = (pkg / "notes.txt").write_text("mine")
...     pkg = write_package(pkg, {"b.py": b"y = 2\\n"}, names)
...     sorted(p.name for p in pkg.iterdir())
['b.py', 'names.json', 'notes.txt']
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

from backends.artifact_io import read_bytes
from backends.atomic import replace_directory, write_file
from ir.errors import ArtifactError, RadarSNNError
from ir.parsing import load_json

__all__ = ["NAMES_FILE", "emitted_entries", "write_package"]

#: The marker file of a generated package (an existing directory without it is never cleared).
NAMES_FILE = "names.json"
#: The files of packages emitted before ``names.json`` listed them (and each stage module).
_FIXED = ("__init__.py", "__main__.py", "_kernels.py", "program.py", "weights.npz")
#: Keys every ``names.json`` emit writes holds (a user's own ``names.json`` is not emit's).
_MARKS = ("package", "chain", "target", "radarsnn_version", "stages")


def _names(folder: Path) -> dict | None:
    """The ``names.json`` body of the package ``folder``; None if it holds no emitted one."""
    try:
        names = load_json(read_bytes(folder / NAMES_FILE).decode("utf-8"), error=ArtifactError)
    except (RadarSNNError, ValueError):  # absent, unreadable, edited
        return None
    return names if isinstance(names, dict) and all(k in names for k in _MARKS) else None


def _listed(names: dict) -> set[str]:
    """The file names a ``names.json`` body says emit wrote (plain names, no folders)."""
    files = names.get("files")
    if files is None:  # an older package: its fixed files, stages and networks
        stages, nets = names.get("stages"), names.get("networks")
        files = [*_FIXED, *(f"{m}.py" for m in (stages.values() if isinstance(stages, dict)
                                                 else ())),
                 *(f"{n.get('module')}.py" for n in (nets if isinstance(nets, list) else ())
                   if isinstance(n, dict))]
    if not isinstance(files, list):
        return set()
    return {f for f in files if isinstance(f, str) and f and "/" not in f and f[0] != "."}


def emitted_entries(folder: Path) -> set[str]:
    """What an earlier emit wrote into ``folder`` (relative paths): all that re-emitting deletes.

    Examples
    --------
    >>> emitted_entries(Path("/nonexistent"))
    set()
    """
    names = _names(folder)
    if names is None:  # not an emitted package: nothing in it is ours
        return set()
    files = _listed(names) | {NAMES_FILE}
    cache = folder / "__pycache__"
    modules = {f[:-3] for f in files if f.endswith(".py")}
    try:
        compiled = [p.name for p in cache.iterdir() if p.name.endswith(".pyc")
                    and p.name.split(".")[0] in modules and p.is_file()]
    except OSError:  # no cache (or not a folder)
        compiled = []
    return files | {"__pycache__", *(f"__pycache__/{n}" for n in compiled)}


def write_package(folder: str | Path, files: Mapping[str, bytes], names: Mapping) -> Path:
    """Create or replace the package ``folder`` holding ``files`` and ``names.json``.

    Parameters
    ----------
    folder : str or Path
        The package directory: new, empty, or a package emitted earlier.
    files : mapping of str to bytes
        File name -> bytes.
    names : mapping
        The body of ``names.json`` (JSON data); the key ``files`` listing every file
        written is added.

    Returns
    -------
    Path
        ``folder``.

    Raises
    ------
    ArtifactError
        ``folder`` exists and is not a generated package, a user's entry in it has
        the name of a new file, or a file cannot be written (the folder is then
        unchanged).
    """
    folder = Path(folder)
    body = {**names, "files": sorted({*files, NAMES_FILE})}
    data = {**files, NAMES_FILE: (json.dumps(body, indent=1, sort_keys=True, ensure_ascii=True)
                                  + "\n").encode()}
    try:
        if folder.is_dir() and _names(folder) is None and any(folder.iterdir()):
            raise ArtifactError(f"{folder}: exists and is not a generated package (no "
                                f"{NAMES_FILE} written by emit); choose another output "
                                "directory or name")
        replace_directory(folder, lambda tmp: [write_file(tmp / n, data[n], sync=False)
                                               for n in sorted(data)],
                          owned=emitted_entries, keep=True, durable=False)
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        raise ArtifactError(f"cannot write the generated package to {folder}: "
                            f"{getattr(exc, 'strerror', None) or exc}") from exc
    return folder
