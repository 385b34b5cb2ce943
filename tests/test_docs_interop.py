"""The demo export figures of docs/interop.md are the recorded output of
``python benchmarks/nir_export.py`` (``benchmarks/results/nir_export.txt``).

The export compiles the 4 x 64 x 256 demo chain (half a minute), so the test compares the page
with the record: the file's size, the report's counts, the shared blocks and their repetitions
(the neurons they feed over the block's rows) and the empty CFAR ``Linear``s.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "interop.md"
RECORD = ROOT / "benchmarks" / "results" / "nir_export.txt"


def _nodes(record: str) -> dict[str, tuple[str, dict[str, tuple[int, ...]]]]:
    """NIR node -> (type, {array: shape}) of the record.

    Examples
    --------
    >>> _nodes("  n1.det.det: IF r (16384,), v_reset (16384,)\\n")
    {'n1.det.det': ('IF', {'r': (16384,), 'v_reset': (16384,)})}
    """
    out = {}
    for line in record.splitlines():
        m = re.match(r"^  (\S+): (\w+) ?(.*)$", line)
        if m:
            arrays = {a: tuple(int(v) for v in shape.split(",") if v.strip())
                      for a, shape in re.findall(r"(\w+) \(([\d, ]*)\)", m.group(3))}
            out[m.group(1)] = (m.group(2), arrays)
    return out


def _num(text: str) -> int:
    return int(text.replace(" ", "").replace("\u202f", ""))


def test_the_export_figures_are_the_recorded_ones() -> None:
    record = RECORD.read_text(encoding="utf-8")
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    size_mb = re.search(r"bytes \(([\d.]+) MB\)", record).group(1)
    counts = dict((k, v) for v, k in re.findall(r"(\d+) (exact|lowered|outside)",
                                                 record.split("\n")[1]))
    quoted = re.search(r"a ([\d.]+) MB file \((\d+) exact, (\d+) lowered and (\d+) outside "
                       r"entries in `carrada\.report\.json`", text)
    assert quoted, "the export's size and counts are not on the page"
    assert quoted.groups() == (size_mb, counts["exact"], counts["lowered"], counts["outside"])
    nodes = _nodes(record)
    for stage, what in (("rng", "block"), ("dop", "block")):
        (rows, cols) = nodes[f"n0.{stage}__moving.w0.compact"][1]["weight"]
        (neurons,) = nodes[f"n0.{stage}__moving.out"][1]["r"]
        m = re.search(rf"`n0\.{stage}__moving\.w0\.compact` \((?:the shared )?([\d ]+) × ([\d ]+)"
                      rf"(?: {what})?(?: of|,) ([\d ]+) repetitions\)", text)
        assert m, stage
        assert (_num(m.group(1)), _num(m.group(2)), _num(m.group(3))) == (
            rows, cols, neurons // rows), stage
    cells = re.search(r"over its ([\d ]+) cells are empty `Linear`s", text)
    assert cells and _num(cells.group(1)) == nodes["n1.det.det"][1]["r"][0]
    cfar = [n for n in nodes if n.startswith("n1.") and nodes[n][0] == "Linear"]
    assert cfar and all(nodes[n][1]["weight"] == (0, 0) for n in cfar)


def test_the_script_still_prints_those_lines() -> None:
    source = (ROOT / "benchmarks" / "nir_export.py").read_text(encoding="utf-8")
    for piece in ("bytes", "MB)", "report entries", '["counts"]', "node/nodes"):
        assert piece in source, piece
