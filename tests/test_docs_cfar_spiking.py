"""The accuracy table of docs/cfar_spiking.md is the recorded output of
``python benchmarks/cfar.py`` (``benchmarks/results/cfar_accuracy.txt``).

The run simulates hundreds of maps at seven step counts (minutes), so the test compares the
page with the record: every sensitivity / precision, the detections per map, the map count and
the codes the page quotes.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "cfar_spiking.md"
RECORD = ROOT / "benchmarks" / "results" / "cfar_accuracy.txt"
#: The page's column names -> the benchmark's case headers.
CASES = {"OS dB": "OS-CFAR on db maps", "CA dB": "CA-CFAR on db maps",
         "OS linear": "OS-CFAR on power maps", "CA linear": "CA-CFAR on power maps"}


def recorded(text: str) -> dict[str, dict]:
    """Per case: detections per map and ``{steps: (sensitivity, precision, code)}``.

    Examples
    --------
    >>> out = recorded("OS-CFAR on db maps, alpha=1.2: 2.5 detections per map (conventional)\\n"
    ...                " steps  sensitivity  precision  code\\n"
    ...                "    10       87.73%     90.54%  log [43.66, 147.2] T=10 cut delay 1\\n")
    >>> out["OS-CFAR on db maps"]["rows"][10]
    ('87.73', '90.54', 'log [43.66, 147.2] T=10 cut delay 1')
    """
    cases, case = {}, None
    for line in text.splitlines():
        head = re.match(r"^(\S.*? maps), alpha=\S+: ([\d.]+) detections per map", line)
        row = re.match(r"^\s+(\d+)\s+([\d.]+)%\s+([\d.]+)%\s+(.+)$", line)
        if head:
            case = cases[head.group(1)] = {"per_map": head.group(2), "rows": {}}
        elif row and case is not None:
            case["rows"][int(row.group(1))] = (row.group(2), row.group(3), row.group(4).strip())
    return cases


def test_the_table_is_the_recorded_run() -> None:
    text = PAGE.read_text(encoding="utf-8")
    record = recorded(RECORD.read_text(encoding="utf-8"))
    lines = [line for line in text.splitlines() if line.startswith("| steps |")]
    assert len(lines) == 1
    header = [c.strip() for c in lines[0].strip("|").split("|")][1:]
    columns = []
    for cell in header:
        name, per_map = re.match(r"^(\w+ \w+) \(([\d.]+)(?: det/map)?\)$", cell).groups()
        assert per_map == record[CASES[name]]["per_map"], cell
        columns.append(CASES[name])
    body = text[text.index(lines[0]):].split("\n\n")[0].splitlines()[2:]
    steps = []
    for line in body:
        cells = [c.strip().replace("*", "") for c in line.strip("|").split("|")]
        steps.append(int(cells[0]))
        for case, cell in zip(columns, cells[1:], strict=True):
            sens, prec, _ = record[case]["rows"][int(cells[0])]
            assert cell == f"{sens} / {prec}", (case, cells[0], cell)
    assert all(sorted(c["rows"]) == steps for c in record.values())


def test_the_quoted_codes_and_map_count_are_the_recorded_ones() -> None:
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    record_text = RECORD.read_text(encoding="utf-8")
    codes = {code for case in recorded(record_text).values() for *_, code in case["rows"].values()}
    quoted = re.findall(r"`((?:log|linear) \[[^`]*\] T=\d+ cut delay \d+)`", text)
    assert quoted and set(quoted) <= codes, quoted
    maps = re.match(r"(\d+) maps \+ (\d+) calibration maps", record_text).groups()
    assert f"python benchmarks/cfar.py --maps {maps[0]}" in text
    assert f"{maps[0]} maps + {maps[1]} calibration maps" in text
