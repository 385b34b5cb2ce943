"""The sections of a sweep file: where its frames come from, its metrics and its figures.

:class:`SceneFrames` (the scene simulator) or :class:`FolderFrames` (``.npy`` files) is
the spec's ``frames``; :class:`MetricSpec` one entry of ``metrics``, :class:`FigureSpec`
one of ``figures``.  The whole file is :class:`radarsnn.sweep.spec.SweepSpec`.

Examples
--------
>>> SceneFrames(n_frames=4, frames_per_cell=2).preset
'carrada'
>>> FolderFrames(source="folder", path="frames", pattern="../x.npy")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pydantic_core._pydantic_core.ValidationError: 1 validation error for FolderFrames
...
"""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PositiveInt,
    field_validator,
    model_validator,
)

from ir.model import short_repr

__all__ = ["FIGURE_NAME", "MAX_PATTERN_CHARS", "MAX_PATTERN_WILDCARDS", "FigureSpec",
           "FolderFrames", "MetricSpec", "SceneFrames"]

#: Longest folder-source ``pattern``, and the most wildcards (``*``, ``?``, ``[``) in it.
MAX_PATTERN_CHARS = 255
MAX_PATTERN_WILDCARDS = 8


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
    """Frames from ``.npy`` files (:func:`radar.readers.read_npy_array`), sorted by name.

    The last ``calibration_frames`` files calibrate, the first ``n_frames`` of the
    others (default all) are scored.  ``labels`` names an ``.npy`` of one integer
    class per file (same order; never itself a frame) for ``classifier_accuracy``.
    ``pattern`` is a glob relative to ``path``: not empty, no ``..`` and no ``**``,
    at most :data:`MAX_PATTERN_CHARS` characters and :data:`MAX_PATTERN_WILDCARDS`
    wildcards (``*``, ``?``, ``[``).
    """

    source: Literal["folder"]
    path: str
    pattern: str = "*.npy"
    n_frames: PositiveInt | None = None
    calibration_frames: PositiveInt = 1
    frames_per_cell: PositiveInt = 25
    labels: str | None = None

    @field_validator("pattern")
    @classmethod
    def _relative_glob(cls, pattern: str) -> str:
        wildcards = sum(pattern.count(c) for c in "*?[")
        parts = pattern.replace("\\", "/").split("/")
        why = ("is empty" if not pattern.strip() else
               f"is {len(pattern)} characters, over {MAX_PATTERN_CHARS}"
               if len(pattern) > MAX_PATTERN_CHARS else
               "holds a NUL byte" if "\0" in pattern else
               "is absolute" if pattern.startswith(("/", "\\")) or pattern[1:2] == ":" else
               "names no file" if not [p for p in parts if p not in ("", ".")] else
               "climbs out of the folder ('..')" if ".." in parts else
               "is recursive ('**')" if "**" in pattern else
               f"has {wildcards} wildcards, over {MAX_PATTERN_WILDCARDS}"
               if wildcards > MAX_PATTERN_WILDCARDS else None)
        if why:
            raise ValueError(f"pattern {short_repr(pattern)} {why}; give a file-name glob "
                             "inside the folder `path`, e.g. '*.npy' or 'run1/frame_*.npy'")
        return pattern


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
