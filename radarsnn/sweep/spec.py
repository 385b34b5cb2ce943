"""The sweep specification: a grid of compile options × a frame source × metrics.

A sweep file (YAML, read with :func:`ir.parsing.load_yaml`) names the chains, the grid and
the frames; :func:`load_spec` validates it into a :class:`SweepSpec` and
:meth:`SweepSpec.points` expands the Cartesian product of the grid into
**points** (one compile each).  A **cell** is one point on one slice of
``frames_per_cell`` frames: the unit of work, of the results file and of
resumption.  Its id is the hash of everything that determines its result
(:func:`~radarsnn.sweep.cells.cell_key`), so a re-run skips cells already done and an edited spec
recomputes exactly the cells it changed.  The file's sections (frames, metrics, figures)
are in :mod:`radarsnn.sweep.sections`, the cell ids in :mod:`radarsnn.sweep.cells`.

Every size is bounded before anything is expanded: the spec's data after YAML alias
expansion (:data:`MAX_SWEEP_EXPANDED_BYTES`, counted without building it), the grid's
points (:data:`MAX_SWEEP_POINTS`, the product of the axis lengths) and the bytes those
points' compile arguments serialise to (:data:`MAX_SWEEP_GRID_BYTES`, from the values'
sizes), and the cells (:data:`MAX_SWEEP_CELLS`, points × slices).

Examples
--------
>>> spec = SweepSpec.model_validate({
...     "name": "tiny", "chains": {"c": {"name": "c", "nodes": [
...         {"id": "x", "op": "input", "shape": {"range": 4}},
...         {"id": "o", "op": "output", "input": "x"}]}},
...     "grid": {"time_steps": [8, 16]},
...     "frames": {"source": "scene", "preset": "carrada", "n_frames": 4,
...                "frames_per_cell": 2}})
>>> [p.params for p in spec.points()]
[{'chain': 'c', 'time_steps': 8}, {'chain': 'c', 'time_steps': 16}]
>>> spec.slices()
[(0, 2), (2, 4)]
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    Field,
    ValidationError,
    model_validator,
)

from backends.reference.run_options import MODES
from ir.errors import CompileError
from ir.model import short_repr
from radarsnn.sweep.sections import FigureSpec, FolderFrames, MetricSpec, SceneFrames, _Model

__all__ = ["SweepSpec", "Point", "load_spec", "parse_spec", "expanded_bytes",
           "MAX_SWEEP_FILE_BYTES", "MAX_SWEEP_EXPANDED_BYTES", "MAX_SWEEP_POINTS",
           "MAX_SWEEP_GRID_BYTES", "MAX_SWEEP_CELLS", "NAMED_AXES"]

#: Largest sweep file read (not a device, not a giant).
MAX_SWEEP_FILE_BYTES = 1 << 20
#: Most bytes a spec may hold once its YAML aliases are expanded (strings by length, every
#: other value 8): 16 MiB, so 120 000 aliases of one 400 KB string are refused unexpanded.
MAX_SWEEP_EXPANDED_BYTES = 16 << 20
#: Most grid points (compiles) of one sweep: the product of the axis lengths.
MAX_SWEEP_POINTS = 10_000
#: Most bytes the points' compile arguments may serialise to, all points together (what
#: hashing the cell ids reads): 256 MiB.
MAX_SWEEP_GRID_BYTES = 256 << 20
#: Most cells (points × slices of ``frames_per_cell`` frames) of one sweep.
MAX_SWEEP_CELLS = 100_000
#: Grid axes besides :data:`compiler.compile.EXTRA_OPTIONS` (each a ``compile_graph`` argument,
#: ``chain`` a key of ``chains``, ``mode`` the simulator engine).
NAMED_AXES = ("chain", "target", "motifs", "calibration", "time_steps", "weight_bits", "mode")


@dataclass(frozen=True)
class Point:
    """One grid point: its axis values and the resolved compile arguments."""

    params: dict[str, Any]
    chain: str
    compile_args: dict[str, Any]
    mode: str
    out_of_range: str = "clip"


class SweepSpec(_Model):
    """A validated sweep file (see ``docs/sweeps.md`` for every field)."""

    name: str
    chains: dict[str, str | dict[str, Any]] = Field(min_length=1)
    grid: dict[str, list[Any]] = Field(default_factory=dict)
    target: str | None = None
    calibration: Literal["static", "per-input"] = "static"
    options: dict[str, Any] = Field(default_factory=dict)
    mode: Literal[MODES] = "step"  # the simulator's modes, from their one home
    out_of_range: Literal["clip", "reject"] = "clip"
    input: str | None = None
    frames: Annotated[SceneFrames | FolderFrames, Field(discriminator="source")]
    metrics: list[MetricSpec] = Field(default_factory=list)
    figures: list[FigureSpec] = Field(default_factory=list)
    base_dir: str = Field(".", description="folder relative paths are read from (the spec's)")

    @model_validator(mode="after")
    def _check(self) -> SweepSpec:
        from compiler.compile import EXTRA_OPTIONS

        known = set(NAMED_AXES) | set(EXTRA_OPTIONS)
        sizes = {}
        for axis, values in self.grid.items():
            if axis not in known:
                raise ValueError(f"grid axis {short_repr(axis)} is not a compile option; known: "
                                 f"{sorted(known)}")
            if not values:
                raise ValueError(f"grid axis {axis!r} has no values; give at least one")
            texts = [json.dumps(v, sort_keys=True, default=str) for v in values]
            if len(set(texts)) != len(texts):
                raise ValueError(f"grid axis {axis!r} repeats a value in {short_repr(values)}; "
                                 "list each once")
            sizes[axis] = [len(t) for t in texts]
        self._check_grid_size(sizes)
        unknown = sorted(set(self.options) - set(EXTRA_OPTIONS))
        if unknown:
            raise ValueError(f"options {unknown} are not compile options; known: "
                             f"{sorted(EXTRA_OPTIONS)}")
        missing = sorted(set(self.grid.get("chain", [])) - set(self.chains))
        if missing:
            raise ValueError(f"grid axis 'chain' names {missing}, not in chains "
                             f"{sorted(self.chains)}")
        if "chain" not in self.grid and len(self.chains) != 1:
            raise ValueError(f"{len(self.chains)} chains {sorted(self.chains)} but no grid axis "
                             "'chain'; add `chain: [...]` to the grid")
        labels = [m.key for m in self.metrics]
        if len(set(labels)) != len(labels):
            raise ValueError(f"metric labels {labels} repeat; give each a distinct `label`")
        files = [f.file_name for f in self.figures]
        if len(set(files)) != len(files):
            raise ValueError(f"figure files {files} repeat (one would overwrite the other); "
                             "give each figure a distinct `name`")
        return self

    def _check_grid_size(self, sizes: dict[str, list[int]]) -> None:
        """Refuse a grid of too many points or bytes, from the axis lengths and value sizes."""
        n_points = math.prod(len(v) for v in sizes.values())
        if n_points > MAX_SWEEP_POINTS:
            lengths = short_repr([len(v) for v in sizes.values()])
            raise ValueError(f"the grid has {n_points} points (the product of its {len(sizes)} "
                             f"axes' lengths {lengths}), over the limit of "
                             f"{MAX_SWEEP_POINTS} (MAX_SWEEP_POINTS); split it into several "
                             "sweeps or drop axes")
        base = len(json.dumps(self.options, sort_keys=True, default=str)) + 64
        grid_bytes = n_points * base + sum(n_points // len(v) * sum(v) for v in sizes.values())
        if grid_bytes > MAX_SWEEP_GRID_BYTES:
            raise ValueError(f"the grid's {n_points} points serialise to {grid_bytes} bytes of "
                             f"compile arguments, over the limit of {MAX_SWEEP_GRID_BYTES} "
                             "(MAX_SWEEP_GRID_BYTES); use fewer points or shorter values")
        if self.frames.source == "scene":
            self.check_cells(math.ceil(self.frames.n_frames / self.frames.frames_per_cell),
                             n_points)

    def n_points(self) -> int:
        """The grid's points: the product of its axis lengths (nothing expanded)."""
        return math.prod(len(v) for v in self.grid.values())

    @staticmethod
    def check_cells(n_slices: int, n_points: int) -> None:
        """Refuse more than :data:`MAX_SWEEP_CELLS` cells (``ValueError`` as a validator
        raises it; :meth:`slices` turns it into a :class:`CompileError`)."""
        if n_slices * n_points > MAX_SWEEP_CELLS:
            raise ValueError(f"{n_points} points x {n_slices} slices of frames = "
                             f"{n_slices * n_points} cells, over the limit of {MAX_SWEEP_CELLS} "
                             "(MAX_SWEEP_CELLS); raise frames_per_cell, score fewer frames or "
                             "use fewer points")

    # ------------------------------------------------------------------ expansion
    def chain_dict(self, name: str) -> dict[str, Any]:
        """The chain ``name`` as a graph dict (a file is read relative to ``base_dir``)."""
        from ir import Graph

        entry = self.chains[name]
        if isinstance(entry, dict):
            return Graph.from_dict(entry).to_dict()
        return Graph.from_yaml(Path(self.base_dir) / entry).to_dict()

    def points(self) -> list[Point]:
        """The grid's points in a fixed order (axes as written, values as listed)."""
        axes = {"chain": list(self.chains)[:1], **self.grid}
        points = []
        for values in itertools.product(*axes.values()):
            params = dict(zip(axes, values, strict=True))
            merged = {"target": self.target, "calibration": self.calibration,
                      "mode": self.mode, **params}
            options = {**self.options, **{k: v for k, v in params.items()
                                          if k not in NAMED_AXES}}
            args = {k: merged.get(k) for k in ("target", "motifs", "calibration",
                                               "time_steps", "weight_bits")}
            points.append(Point(params=params, chain=params["chain"],
                                compile_args={**args, "options": options},
                                mode=merged["mode"], out_of_range=self.out_of_range))
        return points

    def slices(self) -> list[tuple[int, int]]:
        """``(start, stop)`` frame indices of each cell's slice."""
        n, step = self.n_frames(), self.frames.frames_per_cell
        try:
            self.check_cells(math.ceil(n / step), self.n_points())
        except ValueError as err:
            raise CompileError(f"sweep {self.name!r}: {err}") from None
        return [(a, min(a + step, n)) for a in range(0, n, step)]

    def n_frames(self) -> int:
        """Frames scored per point (a folder's count is read from the disk)."""
        if self.frames.source == "scene":
            return self.frames.n_frames
        from radarsnn.sweep.frames import folder_files

        return len(folder_files(self.frames, self.base_dir)[0])


def load_spec(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file; relative paths in it are relative to its folder.

    Parameters
    ----------
    path : str or Path
        A YAML file of at most :data:`MAX_SWEEP_FILE_BYTES` (read with
        :func:`ir.parsing.load_yaml`: no code runs, nesting and aliases bounded).

    Returns
    -------
    SweepSpec

    Raises
    ------
    CompileError
        Unreadable file, invalid YAML, or a field that breaks a rule (named, with
        the value given and the rule).

    Examples
    --------
    >>> load_spec("examples/sweeps/small.yaml").name
    'small'
    """
    from ir.serialize import load_yaml_mapping

    path = Path(path)
    try:
        if not path.is_file() or path.stat().st_size > MAX_SWEEP_FILE_BYTES:
            raise CompileError(f"sweep file {str(path)!r} cannot be read: not a regular file "
                               f"of at most {MAX_SWEEP_FILE_BYTES} bytes")
        text = path.read_text(encoding="utf-8")
    except (OSError, ValueError) as err:  # UnicodeDecodeError; a NUL byte in the path
        why = getattr(err, "strerror", None) or err
        raise CompileError(f"sweep file {str(path)!r} cannot be read: {why}") from None
    data = load_yaml_mapping(text, f"sweep file {str(path)!r}", "sweep fields",
                             error=CompileError)
    data.setdefault("base_dir", str(path.parent))
    return parse_spec(data, label=f"sweep file {str(path)!r}")


def parse_spec(data: dict[str, Any], *, label: str = "sweep spec") -> SweepSpec:
    """Validate a sweep dict; pydantic's errors become one :class:`CompileError`.

    Examples
    --------
    >>> parse_spec({"name": "x"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: sweep spec: field 'chains': Field required; field 'frames': ...
    """
    size = expanded_bytes(data, MAX_SWEEP_EXPANDED_BYTES)
    if size > MAX_SWEEP_EXPANDED_BYTES:
        raise CompileError(f"{label}: more than {MAX_SWEEP_EXPANDED_BYTES} bytes once its "
                           "aliases are expanded (MAX_SWEEP_EXPANDED_BYTES); write the values "
                           "out, or share fewer large ones")
    try:
        return SweepSpec.model_validate(data)
    except ValidationError as err:
        parts = []
        for item in err.errors(include_url=False)[:8]:
            where = ".".join(str(p)[:40] for p in item["loc"]) or "<spec>"
            given = (f" (given {short_repr(item['input'])})" if item["type"] != "missing"
                     else "")
            parts.append(f"field {where!r}: {str(item['msg'])[:400]}{given}")
        raise CompileError(f"{label}: " + "; ".join(parts)) from None


def expanded_bytes(data: Any, limit: int) -> int:
    """The bytes ``data`` would hold with every shared value copied: strings by their length,
    keys included, anything else 8; counting stops past ``limit`` (so a cycle or an alias
    bomb costs at most ``limit`` steps).

    Examples
    --------
    >>> big = "x" * 1000
    >>> expanded_bytes({"a": [big] * 3}, 10**6), expanded_bytes([big] * 10**6, 5000) > 5000
    (3017, True)
    """
    total, stack = 0, [data]
    while stack and total <= limit:
        item = stack.pop()
        if isinstance(item, str | bytes):
            total += len(item)
        elif isinstance(item, dict):
            total += 8
            for key, value in item.items():
                stack += (key, value)
                if len(stack) > limit:
                    break
        elif isinstance(item, list | tuple):
            total += 8
            stack.extend(item[:limit - len(stack) + 1])
        else:
            total += 8
    return total
