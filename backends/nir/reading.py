r"""Read a NIR file (HDF5) within bounds, every failure an :class:`ArtifactError`.

``nir.read`` trusts its file: it recurses through groups without a depth limit,
follows hard-link cycles until ``RecursionError``, and reads every dataset whole
(a few kilobytes of gzip'd zeros can declare gigabytes).  :func:`read_nir` walks
the file itself with ``h5py`` and checks, before anything is read:

* the file size (``max_file_bytes``);
* the group nesting (``max_depth``) and the number of objects (``max_objects``);
* links: only hard links, none to a group on its own path (a cycle), and no object
  reached twice (``nir.write`` writes a tree; a diamond of links would multiply the walk);
* each dataset's dtype (numbers, booleans or strings only) and its size from the
  declared shape (``max_dataset_entries`` entries, ``max_total_bytes`` in all),
  never by decompressing it;
* every string decodes as UTF-8.

The tree is then built into NIR nodes one by one with ``nir``'s own
constructors; an error of theirs is re-raised as an :class:`ArtifactError`
naming the file and the node path (``/node/nodes/<name>``).

Examples
--------
>>> import tempfile, pathlib, nir, numpy as np
>>> with tempfile.TemporaryDirectory() as d:
...     path = pathlib.Path(d) / "g.nir"
...     nir.write(path, nir.NIRGraph.from_list(nir.Linear(weight=np.ones((1, 2)))))
...     sorted(read_nir(path).nodes)
['input', 'linear', 'output']
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import nir
import numpy as np

from ir.errors import ArtifactError

__all__ = ["DEFAULT_BOUNDS", "ReadBounds", "read_nir"]

#: Dtype kinds a NIR dataset may have: floats, signed/unsigned integers, booleans, byte strings.
_KINDS = frozenset("fiubS")


@dataclass(frozen=True)
class ReadBounds:
    """Limits :func:`read_nir` checks before it reads (docs/reliability.md, *NIR files*).

    Attributes
    ----------
    max_file_bytes : int
        Largest file read (1 GiB).
    max_depth : int
        Deepest group nesting (32; a radarsnn export uses 5).
    max_objects : int
        Groups and datasets in the file (2^16; each is reached once).
    max_dataset_entries : int
        Largest dataset, in entries (2^24, the export's ``MAX_WEIGHTS``).
    max_total_bytes : int
        All datasets together, from their declared shapes and dtypes (1 GiB).
    """

    max_file_bytes: int = 1 << 30
    max_depth: int = 32
    max_objects: int = 1 << 16
    max_dataset_entries: int = 1 << 24
    max_total_bytes: int = 1 << 30


#: The bounds :func:`read_nir` applies unless told otherwise.
DEFAULT_BOUNDS = ReadBounds()


class _Walk:
    """One bounded walk of a file: the counters and the file name for messages."""

    def __init__(self, path: Path, bounds: ReadBounds) -> None:
        self.path, self.bounds = path, bounds
        self.objects = 0
        self.total_bytes = 0
        self.seen: set[int] = set()  # HDF5 addresses of the objects reached

    def fail(self, where: str, message: str) -> ArtifactError:
        return ArtifactError(f"NIR file {self.path}: {where}: {message}", node=where)

    def group(self, group: h5py.Group, where: str, on_path: tuple) -> dict[str, Any]:
        b = self.bounds
        if len(on_path) > b.max_depth:
            raise self.fail(where, f"groups nest deeper than max_depth={b.max_depth}; not a "
                                   "NIR graph radarsnn reads")
        out: dict[str, Any] = {}
        for name in group:
            here = f"{where}/{name}"
            self.objects += 1
            if self.objects > b.max_objects:
                raise self.fail(here, f"more than max_objects={b.max_objects} groups and "
                                      "datasets")
            link = group.get(name, getlink=True)
            if not isinstance(link, h5py.HardLink):
                raise self.fail(here, f"is a {type(link).__name__}; a NIR file holds only "
                                      "hard links (soft and external links are refused)")
            item = group[name]
            address = h5py.h5o.get_info(item.id).addr
            if address in on_path:
                raise self.fail(here, "links back to a group on its own path (a cycle)")
            if address in self.seen:
                raise self.fail(here, "is a second hard link to an object already read; a NIR "
                                      "file is a tree")
            self.seen.add(address)
            if isinstance(item, h5py.Group):
                out[name] = self.group(item, here, (*on_path, address))
            elif isinstance(item, h5py.Dataset):
                out[name] = self.dataset(item, here)
            else:
                raise self.fail(here, f"is a {type(item).__name__}, not a group or dataset")
        return out

    def dataset(self, ds: h5py.Dataset, where: str) -> Any:
        b = self.bounds
        dtype = ds.dtype
        string = h5py.check_string_dtype(dtype)
        if string is None and dtype.kind not in _KINDS:
            raise self.fail(where, f"dtype {dtype} is not a number, boolean or string")
        if ds.shape is None:
            raise self.fail(where, "is an empty (null-dataspace) dataset")
        entries = int(np.prod(ds.shape, dtype=np.int64)) if ds.shape else 1
        if entries > b.max_dataset_entries:
            raise self.fail(where, f"shape {ds.shape} declares {entries} entries, over "
                                   f"max_dataset_entries={b.max_dataset_entries}")
        self.total_bytes += entries * max(dtype.itemsize, 8 if string else 1)
        if self.total_bytes > b.max_total_bytes:
            raise self.fail(where, f"the datasets declare more than max_total_bytes="
                                   f"{b.max_total_bytes} bytes in all")
        try:
            value = ds[()]
        except (OSError, ValueError, TypeError, RuntimeError) as exc:  # a damaged chunk
            text = str(exc).splitlines()[0] if str(exc) else ""
            raise self.fail(where, f"cannot be read ({type(exc).__name__}: {text[:200]})"
                            ) from None
        return _text(value, self, where) if string is not None or dtype.kind == "S" else value


def _text(value: Any, walk: _Walk, where: str) -> Any:
    """Bytes as ``str`` (arrays of bytes stay arrays, elementwise checked), or a typed error."""
    try:
        if isinstance(value, bytes):
            return value.decode("utf-8")
        if isinstance(value, np.ndarray):
            for item in value.ravel():
                if isinstance(item, bytes):
                    item.decode("utf-8")
        return value
    except UnicodeDecodeError as exc:
        raise walk.fail(where, f"a string is not UTF-8 ({exc.reason} at byte {exc.start})"
                        ) from None


def _build(data: Any, walk: _Walk, where: str, type_check: bool) -> nir.NIRNode:
    """One NIR node (a graph's children first) from its dict, with ``nir``'s constructors."""
    if not isinstance(data, dict) or not isinstance(data.get("type"), str):
        raise walk.fail(where, "is not a NIR node (a group with a string `type`)")
    data = dict(data)
    try:
        if data["type"] == "NIRGraph":
            children = data.get("nodes")
            edges = np.asarray(data.get("edges", np.zeros((0, 2), dtype=object)))
            if not isinstance(children, dict) or edges.ndim != 2 or edges.shape[1:] != (2,):
                raise walk.fail(where, "a NIRGraph needs a `nodes` group and an (n, 2) "
                                       "`edges` dataset of names")
            nodes = {k: _build(v, walk, f"{where}/nodes/{k}", type_check)
                     for k, v in children.items()}
            pairs = [(_name(a, walk, where), _name(b, walk, where)) for a, b in edges]
            return nir.NIRGraph(nodes=nodes, edges=pairs, metadata=data.get("metadata", {}),
                                type_check=type_check)
        return nir.dict2NIRNode(data)
    except ArtifactError:
        raise
    except Exception as exc:  # nir's constructors on untrusted data: any error is a bad file
        text = str(exc).splitlines()[0] if str(exc) else ""
        raise walk.fail(where, f"nir refuses the {data.get('type')} node "
                               f"({type(exc).__name__}: {text[:200]})") from None


def _name(value: Any, walk: _Walk, where: str) -> str:
    if isinstance(value, bytes):
        value = _text(value, walk, f"{where}/edges")
    if not isinstance(value, str):
        raise walk.fail(f"{where}/edges", f"an edge end {value!r} is not a node name")
    return value


def read_nir(path: str | Path, *, bounds: ReadBounds = DEFAULT_BOUNDS,
             type_check: bool = True) -> nir.NIRGraph:
    """Read a NIR graph file within ``bounds`` (no code runs; nothing unbounded is read).

    Parameters
    ----------
    path : str or Path
        The ``.nir`` file.
    bounds : ReadBounds
        The limits checked before reading (see the module doc).
    type_check : bool
        Let ``nir`` check that the shapes along every edge agree (``nir.read``'s default);
        radarsnn's compact projections (docs/interop.md) need ``False``.

    Returns
    -------
    nir.NIRGraph

    Raises
    ------
    ArtifactError
        One line naming the file, the HDF5 path and the limit or the fault: not a file,
        not HDF5, over a bound, a soft/external link or a cycle, a dtype, a string that
        is not UTF-8, or a node ``nir`` refuses.
    """
    path = Path(path)
    walk = _Walk(path, bounds)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ArtifactError(f"NIR file {path}: cannot read ({exc.strerror or exc})") from None
    if not path.is_file():
        raise ArtifactError(f"NIR file {path}: is not a file")
    if size > bounds.max_file_bytes:
        raise ArtifactError(f"NIR file {path}: {size} bytes, over max_file_bytes="
                            f"{bounds.max_file_bytes}")
    try:
        with h5py.File(path, "r") as f:
            if not isinstance(f.get("node", getlink=True), h5py.HardLink) or not isinstance(
                    f["node"], h5py.Group):
                raise walk.fail("/node", "missing: not a NIR file (no `node` group)")
            root = h5py.h5o.get_info(f.id).addr
            tree = walk.group(f["node"], "/node", (root, h5py.h5o.get_info(f["node"].id).addr))
    except ArtifactError:
        raise
    except (OSError, KeyError, ValueError, TypeError, RuntimeError, UnicodeDecodeError) as exc:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ArtifactError(f"NIR file {path}: not a readable HDF5 NIR file "
                            f"({type(exc).__name__}: {text[:200]})") from None
    kind = tree.get("type")
    if not (isinstance(kind, str) and kind == "NIRGraph"):
        raise walk.fail("/node", f"the root's type is {str(kind)[:40]!r}, not 'NIRGraph'")
    return _build(tree, walk, "/node", type_check)
