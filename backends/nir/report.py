"""The export report: what of a spiking network NIR holds exactly, by construction, or not at all.

Every population, projection, encoder and decoder of an exported network gets
one :class:`ReportEntry` per aspect, of one of three kinds:

``exact``     mapped one-to-one onto a NIR node (e.g. a delay-free ``Linear``);
``lowered``   rewritten into an equivalent NIR construction (per-synapse delays
              → one ``Delay`` + ``Linear`` per delay class, ``v >= v_th`` →
              ``v > nextafter(v_th, -inf)``, a constant bias → ``v_leak``, …);
``outside``   not expressible in NIR: kept in the node's ``radarsnn_*``
              metadata and to be run by the consumer (bias schedules, fire-once,
              latency encoders, decoders, host segments).

Nothing is dropped silently: a consumer that ignores the ``outside`` entries
knows exactly which behaviour it loses.

Examples
--------
>>> r = ExportReport(path=None)
>>> r.add("adc/in", "encoder", "outside", "latency code runs before the graph")
>>> r.add("p", "reset", "outside", "fire-once")
>>> [e.item for e in r.outside], r.is_exact
(['adc/in', 'p'], False)
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

from backends.atomic import write_atomic

__all__ = ["ReportEntry", "ExportReport", "EntryKind"]

EntryKind = Literal["exact", "lowered", "outside"]


@dataclass(frozen=True)
class ReportEntry:
    """One aspect of one exported item.

    Attributes
    ----------
    item : str
        Population, projection or port id (or an IR node id for host segments).
    aspect : str
        What is described (``neuron``, ``threshold``, ``bias``, ``reset``, ``delays``, …).
    kind : {"exact", "lowered", "outside"}
        How NIR holds it (see the module doc).
    detail : str
        One sentence naming the NIR nodes or the lost behaviour.
    """

    item: str
    aspect: str
    kind: EntryKind
    detail: str


@dataclass
class ExportReport:
    """All entries of one export, and where the graph was written.

    Attributes
    ----------
    path : str or None
        The ``.nir`` file, once written.
    entries : list of ReportEntry
    nodes : dict of str to str
        Every NIR node name and the population/projection/port it came from.
    """

    path: str | None = None
    entries: list[ReportEntry] = field(default_factory=list)
    nodes: dict[str, str] = field(default_factory=dict)

    def add(self, item: str, aspect: str, kind: EntryKind, detail: str) -> None:
        """Record one entry."""
        self.entries.append(ReportEntry(item, aspect, kind, detail))

    @property
    def outside(self) -> list[ReportEntry]:
        """The entries NIR cannot express (kept in metadata only)."""
        return [e for e in self.entries if e.kind == "outside"]

    @property
    def is_exact(self) -> bool:
        """True when only the port codes are ``outside``: given the input spikes, the NIR graph
        reproduces every spike of the network (encoders and decoders always run outside)."""
        return all(e.aspect in ("encoder", "decoder", "host segment") for e in self.outside)

    def to_dict(self) -> dict:
        """JSON-able form: counts per kind, entries, node origins.

        Examples
        --------
        >>> r = ExportReport()
        >>> r.add("w", "weights", "exact", "Linear w")
        >>> r.to_dict()["counts"]
        {'exact': 1, 'lowered': 0, 'outside': 0}
        """
        counts = {k: sum(e.kind == k for e in self.entries)
                  for k in ("exact", "lowered", "outside")}
        return {"path": self.path, "counts": counts,
                "entries": [asdict(e) for e in self.entries], "nodes": dict(self.nodes)}

    def to_bytes(self) -> bytes:
        """The report as the JSON file :meth:`write` writes."""
        return (json.dumps(self.to_dict(), indent=2) + "\n").encode()

    def write(self, path: str | Path) -> Path:
        """Write the report as JSON to ``path`` atomically (whole, or not at all); returns it."""
        path = Path(path)
        write_atomic(path, self.to_bytes())
        return path

    def summary(self) -> str:
        """A few lines for humans: the counts and every ``outside`` entry.

        Examples
        --------
        >>> r = ExportReport()
        >>> r.add("p", "reset", "outside", "fire-once is not a NIR reset")
        >>> print(r.summary())
        NIR export: 0 exact, 0 lowered, 1 outside NIR
          outside: p reset: fire-once is not a NIR reset
        """
        c = self.to_dict()["counts"]
        lines = [f"NIR export: {c['exact']} exact, {c['lowered']} lowered, {c['outside']} "
                 "outside NIR"]
        lines += [f"  outside: {e.item} {e.aspect}: {e.detail}" for e in self.outside]
        return "\n".join(lines)
