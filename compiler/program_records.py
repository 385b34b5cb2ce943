"""What the passes learned about a program, as typed fields: :class:`ProgramRecords`.

Every built-in pass writes one field — the rewrites of ``fuse-linear``, the static
split, the calibration, the motif chosen per node, the quantization, the split and
the placement, the report, the pass timings (and ``radarsnn compile``'s accuracy
check).  A pass of the user's own keeps its record under its name in
:attr:`ProgramRecords.extra`.

For code written against the earlier dictionary, the record is also a mapping from
the pass's name to its field (``records["report"]`` is ``records.report``); a field
that is still empty is absent from the mapping.

Examples
--------
>>> r = ProgramRecords()
>>> dict(r), r.report is None
({}, True)
>>> r["timings"] = {"verify": 0.1}
>>> r.timings, list(r), r.get("placement") is None
({'verify': 0.1}, ['timings'], True)
>>> r["count"] = 2  # a user pass
>>> r.extra, r["count"]
({'count': 2}, 2)
"""

from __future__ import annotations

from collections.abc import Iterator, MutableMapping
from dataclasses import dataclass, field, fields
from typing import Any

__all__ = ["RECORD_FIELDS", "ProgramRecords"]

_FIELD_NAMES = frozenset(("rewrites", "static_splits", "calibration", "lowering",
                          "quantization", "splits", "placement", "report", "timings",
                          "accuracy"))

#: The pass (or tool) name each typed field belongs to.
RECORD_FIELDS = {
    "fuse-linear": "rewrites", "static-split": "static_splits", "calibrate": "calibration",
    "lower": "lowering", "quantize": "quantization", "split": "splits",
    "placement": "placement", "report": "report", "timings": "timings",
    "accuracy": "accuracy",
}


@dataclass(eq=False)  # equality is the mapping's (records == {} for a fresh program)
class ProgramRecords(MutableMapping):
    """Typed records of a compiled program (see the module docstring).

    Attributes
    ----------
    rewrites : list of dict
        ``fuse-linear``: every rewrite (rule, into, folded …).
    static_splits : list of dict
        ``static-split``: per split, the Doppler node, the input, the moving part.
    calibration : Calibration or None
        ``calibrate``: :class:`compiler.calibration.Calibration`.
    lowering : dict
        ``lower``: ``{"motifs": {node: motif}}``, the motif chosen for every node.
    quantization : list
        ``quantize``: one record per spiking segment.
    splits : list
        ``split`` (and ``place``'s escalation): one :class:`SplitRecord` per network.
    placement : Placement or None
        ``place``: blocks on cores and chips.
    report : Report or None
        ``report``: :class:`compiler.report.Report`.
    timings : dict of str to float
        Seconds per pass.
    accuracy : object or None
        ``radarsnn compile``'s :class:`backends.reference.accuracy.AccuracyCheck`.
    extra : dict
        Records of passes of the user's own, by pass name.
    """

    rewrites: list = field(default_factory=list)
    static_splits: list = field(default_factory=list)
    calibration: Any = None
    lowering: dict = field(default_factory=dict)
    quantization: list = field(default_factory=list)
    splits: list = field(default_factory=list)
    placement: Any = None
    report: Any = None
    timings: dict = field(default_factory=dict)
    accuracy: Any = None
    extra: dict = field(default_factory=dict)
    _written: set = field(default_factory=set, repr=False)

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _FIELD_NAMES and "_written" in self.__dict__:  # a pass wrote its record
            self._written.add(name)
        object.__setattr__(self, name, value)

    @property
    def motifs(self) -> dict[str, str]:
        """The motif chosen for every node (``lower``)."""
        return dict(self.lowering.get("motifs", {}))

    # ------------------------------------------------ the mapping by pass name
    def _present(self, name: str) -> bool:
        """Written by its pass (even an empty list), or holding something."""
        value = getattr(self, name)
        return name in self._written or not (
            value is None or (isinstance(value, list | dict) and not value))

    def __getitem__(self, key: str) -> Any:
        name = RECORD_FIELDS.get(key)
        if name is None:
            return self.extra[key]
        if not self._present(name):
            raise KeyError(key)
        return getattr(self, name)

    def __setitem__(self, key: str, value: Any) -> None:
        name = RECORD_FIELDS.get(key)
        if name is None:
            self.extra[key] = value
        else:
            setattr(self, name, value)

    def __delitem__(self, key: str) -> None:
        name = RECORD_FIELDS.get(key)
        if name is None:
            del self.extra[key]
            return
        default = next(f for f in fields(self) if f.name == name)
        object.__setattr__(self, name, default.default_factory()
                           if callable(default.default_factory) else default.default)
        self._written.discard(name)

    def __iter__(self) -> Iterator[str]:
        yield from (k for k, name in RECORD_FIELDS.items() if self._present(name))
        yield from self.extra

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def setdefault(self, key: str, default: Any = None) -> Any:
        """``records.setdefault("timings", {})`` as on a dict (the field itself)."""
        if key not in self:
            self[key] = default
        return self[key]
