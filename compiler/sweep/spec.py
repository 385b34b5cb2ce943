"""The sweep specification: a grid of compile options × a frame source × metrics.

A sweep file (YAML, read with :func:`ir.parsing.load_yaml`) names the chains, the grid and
the frames; :func:`load_spec` validates it into a :class:`SweepSpec` and
:meth:`SweepSpec.points` expands the Cartesian product of the grid into
**points** (one compile each).  A **cell** is one point on one slice of
``frames_per_cell`` frames: the unit of work, of the results file and of
resumption.  Its id is the hash of everything that determines its result
(:func:`cell_key`), so a re-run skips cells already done and an edited spec
recomputes exactly the cells it changed.

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

import hashlib
import itertools
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PositiveInt,
    ValidationError,
    field_validator,
    model_validator,
)

from ir.errors import CompileError

__all__ = ["SceneFrames", "FolderFrames", "MetricSpec", "FigureSpec", "SweepSpec", "Point",
           "load_spec", "parse_spec", "cell_key", "MAX_SWEEP_FILE_BYTES", "NAMED_AXES"]

#: Largest sweep file read (not a device, not a giant).
MAX_SWEEP_FILE_BYTES = 1 << 20
#: Grid axes besides :data:`compiler.compile.EXTRA_OPTIONS` (each a ``compile_graph`` argument,
#: ``chain`` a key of ``chains``, ``mode`` the simulator engine).
NAMED_AXES = ("chain", "target", "motifs", "calibration", "time_steps", "weight_bits", "mode")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SceneFrames(_Model):
    """Frames from the scene simulator (:func:`radar.scene.simulate_frame`).

    Frame ``i`` is simulated with the seed ``SeedSequence([seed, 0, i])`` (its
    random scene too, for ``scene: random``), calibration frame ``j`` with
    ``SeedSequence([seed, 1, j])``: a frame does not depend on ``n_frames``, the
    worker that makes it, nor on the order of the work.
    """

    source: Literal["scene"] = "scene"
    preset: str = "carrada"
    scene: str = Field("random", description="a radar.scene.SCENE_PRESETS name or 'random'")
    product: Literal["adc", "rd_power", "rd_db"] = "adc"
    n_frames: PositiveInt = 100
    seed: int = Field(0, ge=0)
    calibration_frames: PositiveInt = 8
    frames_per_cell: PositiveInt = 25


class FolderFrames(_Model):
    """Frames from ``.npy`` files (``np.load(..., allow_pickle=False)``), sorted by name.

    The last ``calibration_frames`` files calibrate, the first ``n_frames`` of the
    others (default all) are scored.  ``labels`` names an ``.npy`` of one integer
    class per file (same order; never itself a frame) for ``classifier_accuracy``.
    """

    source: Literal["folder"]
    path: str
    pattern: str = "*.npy"
    n_frames: PositiveInt | None = None
    calibration_frames: PositiveInt = 1
    frames_per_cell: PositiveInt = 25
    labels: str | None = None


class MetricSpec(_Model):
    """One metric of every cell: a registered metric ``name``, its ``node``, its options."""

    name: str
    label: str | None = None
    node: str | None = None
    options: dict[str, Any] = Field(default_factory=dict)

    @property
    def key(self) -> str:
        """The metric's column name in the summary (``label`` or ``name``)."""
        return self.label or self.name


#: A figure's file name (``<name>.png`` in ``OUT/figures``): a plain name, never a path.
FIGURE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")


class FigureSpec(_Model):
    """One figure of the sweep (a bare string in the file is its ``kind``).

    ``metric`` is ``KEY`` or ``KEY.FIELD`` of a metric (default: the first metric of the
    kind's metric name, its main field); ``x`` a grid axis; ``cost`` a cost column;
    ``name`` the file name (``<name>.png``, default the kind): letters, digits, ``_``,
    ``-`` and ``.``, at most 100, no folder.

    Examples
    --------
    >>> FigureSpec(kind="pareto", name="rmse_vs_cost").file_name
    'rmse_vs_cost.png'
    >>> [bool(FIGURE_NAME.fullmatch(n)) for n in ("fig7.a", "../../x", "/abs/y", ".hidden")]
    [True, False, False, False]
    """

    kind: Literal["fig7", "sft_rmse", "weight_bits", "pareto"]
    metric: str | None = None
    x: str | None = None
    cost: str | None = None
    name: str | None = None

    @model_validator(mode="before")
    @classmethod
    def _from_name(cls, data: Any) -> Any:
        return {"kind": data} if isinstance(data, str) else data

    @field_validator("name")
    @classmethod
    def _plain_name(cls, name: str | None) -> str | None:
        if name is not None and not FIGURE_NAME.fullmatch(name):
            raise ValueError("a figure name is a file name in OUT/figures, not a path: "
                             "letters, digits, '_', '-' and '.' (first a letter or digit, at "
                             "most 100), e.g. 'fig7_carrada'")
        return name

    @property
    def file_name(self) -> str:
        """``<name or kind>.png``."""
        return f"{self.name or self.kind}.png"


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
    mode: Literal["step", "closed", "auto"] = "step"
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
        for axis, values in self.grid.items():
            if axis not in known:
                raise ValueError(f"grid axis {axis!r} is not a compile option; known: "
                                 f"{sorted(known)}")
            if not values:
                raise ValueError(f"grid axis {axis!r} has no values; give at least one")
            texts = [json.dumps(v, sort_keys=True) for v in values]
            if len(set(texts)) != len(texts):
                raise ValueError(f"grid axis {axis!r} repeats a value in {values}; list each once")
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
        return [(a, min(a + step, n)) for a in range(0, n, step)]

    def n_frames(self) -> int:
        """Frames scored per point (a folder's count is read from the disk)."""
        if self.frames.source == "scene":
            return self.frames.n_frames
        from compiler.sweep.frames import folder_files

        return len(folder_files(self.frames, self.base_dir)[0])


def cell_key(*parts: Any) -> str:
    """16 hex digits of the SHA-256 of the canonical JSON of ``parts``.

    Examples
    --------
    >>> cell_key({"b": 1, "a": [1, 2]}, (0, 25)) == cell_key({"a": [1, 2], "b": 1}, [0, 25])
    True
    >>> len(cell_key("x"))
    16
    """
    text = json.dumps(parts, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


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
    from ir.parsing import load_yaml

    path = Path(path)
    try:
        if not path.is_file() or path.stat().st_size > MAX_SWEEP_FILE_BYTES:
            raise CompileError(f"sweep file {str(path)!r} cannot be read: not a regular file "
                               f"of at most {MAX_SWEEP_FILE_BYTES} bytes")
        data = load_yaml(path.read_text(encoding="utf-8"), error=CompileError)
    except (OSError, ValueError) as err:  # UnicodeDecodeError; a NUL byte in the path
        why = getattr(err, "strerror", None) or err
        raise CompileError(f"sweep file {str(path)!r} cannot be read: {why}") from None
    except yaml.YAMLError as err:
        raise CompileError(f"sweep file {str(path)!r}: not valid YAML: {err}") from None
    except CompileError as err:
        raise CompileError(f"sweep file {str(path)!r}: {err}") from None
    if not isinstance(data, dict):
        raise CompileError(f"sweep file {str(path)!r}: expected a mapping of sweep fields, got "
                           f"{type(data).__name__}")
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
    try:
        return SweepSpec.model_validate(data)
    except ValidationError as err:
        parts = []
        for item in err.errors(include_url=False):
            where = ".".join(str(p) for p in item["loc"]) or "<spec>"
            given = f" (given {item['input']!r})" if item["type"] != "missing" else ""
            parts.append(f"field {where!r}: {item['msg']}{given}")
        raise CompileError(f"{label}: " + "; ".join(parts)) from None
