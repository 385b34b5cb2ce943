"""The measured figures of docs/reliability.md are recorded runs of the commands it names.

* *Input bounds*: the cells marked ¹ are ``python benchmarks/hostile_inputs.py``
  (``benchmarks/results/hostile_inputs.txt``): each file's size, the seconds and the memory
  growth of the call, to the digits quoted.
* *Closed-mode scaling*: the table is ``python benchmarks/closed_scaling.py``
  (``benchmarks/results/closed_scaling.txt``), and its ratios are the recorded seconds'.

Timings are never asserted against a new run; the last test checks that the benchmark still
builds every case the page quotes.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "reliability.md"
RESULTS = ROOT / "benchmarks" / "results"

#: Row of the input-bounds table -> (the benchmark's case, what its cell says of it).
CELLS = {
    "YAML loader": ("chain, 28 000 nodes, valid",
                    "a valid {bytes}-byte chain (28 000 nodes): read in {time}, {growth}¹"),
    "chain file size": ("chain, 28 000 nodes, valid",
                        "the valid 28 000-node chain of *YAML loader* is {bytes} bytes¹"),
    "YAML nodes after alias expansion": ("chain, billion laughs (9^9 strings) as name",
                                         'a {bytes}-byte "billion laughs" (9⁹ strings) as a '
                                         "chain's `name`: refused in {time}, {growth}¹"),
    "nesting depth": ("chain, 5 000 nested [ as name",
                      "5 000 `[` as a chain's `name` (a {bytes}-byte file): refused in {time}, "
                      "{growth}¹"),
    "`.npz` inputs": (".npz member declaring 3.9 GiB, port (4,)",
                      "a {bytes}-byte deflate bomb declaring 3.9 GiB for a port `(4,)`: refused "
                      "in {time}, {growth}¹"),
    "`.mat` inputs": (".mat 1x1 double, 3.9 GiB data element",
                      "a {bytes}-byte file declaring a 1 × 1 double whose data element inflates "
                      "to 3.9 GiB: refused in {time}, {growth}¹"),
    "TI `.bin` inputs": (".bin 96 MiB, decoded",
                         "a 96 MiB capture (384 MiB of complex128): peak growth {mib} MiB, "
                         "{time}¹"),
    "sweep spec, expanded": ("sweep, 120 000 aliases of 400 KB",
                             "an {bytes}-byte file whose `mode` holds 120 000 aliases of a 400 KB "
                             "string: refused in {time} (the YAML parse), {growth}¹"),
    "sweep grid": ("sweep, 33 axes x 2 values, planned",
                   "33 axes of 2 values (2³³ points, a {bytes}-byte file): refused in {time}¹"),
}


def spaced(n: int) -> str:
    """``1 024 911`` for 1024911 (the pages' digit groups)."""
    return f"{n:,}".replace(",", " ")


def seconds(s: float) -> str:
    """A recorded time as the page writes it: two digits, in ms below 0.1 s.

    Examples
    --------
    >>> seconds(0.0014), seconds(0.3903), seconds(3.7088)
    ('1.4 ms', '0.4 s', '3.7 s')
    """
    return f"{s * 1e3:.1f} ms" if s < 0.1 else f"{s:.1f} s"


def _hostile() -> dict[str, tuple[int, float, int, str]]:
    out = {}
    for line in (RESULTS / "hostile_inputs.txt").read_text(encoding="utf-8").splitlines():
        m = re.match(r"^(.+?)\s+(\d+) B\s+([\d.]+) s\s+(\d+) MiB  (.*)$", line)
        if m:
            out[m.group(1)] = (int(m.group(2)), float(m.group(3)), int(m.group(4)), m.group(5))
    return out


def test_the_input_bound_figures_are_the_recorded_run() -> None:
    record = _hostile()
    text = PAGE.read_text(encoding="utf-8")
    table = text[text.index("| bound | value | where | measured |"):].split("\n\n")[0]
    rows = {line.split("|")[1].strip(): line for line in table.splitlines()}
    for row, (case, cell) in CELLS.items():
        size, secs, mib, end = record[case]
        growth = "no memory growth" if mib == 0 else f"{mib} MiB growth"
        expected = cell.format(bytes=spaced(size), time=seconds(secs), growth=growth, mib=mib)
        assert expected in rows[row], (row, expected)
        assert (end == "read") == ("refused" not in cell), (case, end)
    marked = [name for name, line in rows.items() if "¹" in line.split("|")[4]]
    assert sorted(marked) == sorted(CELLS)


def test_the_closed_scaling_table_is_the_recorded_run() -> None:
    record = (RESULTS / "closed_scaling.txt").read_text(encoding="utf-8")
    runs = [[float(v) for v in line.split()] for line in record.splitlines()
            if re.match(r"^\s+\d+\s+[\d.]+", line)]
    text = PAGE.read_text(encoding="utf-8")
    table = text[text.index("| frames | 1 000 |"):].split("\n\n")[0].splitlines()
    cells = {line.split("|")[1].strip(): [c.strip() for c in line.strip("|").split("|")[1:]]
             for line in table if not line.startswith("| ---")}
    assert [int(c.replace(" ", "")) for c in cells["frames"]] == [int(r[0]) for r in runs]
    for label, col, fmt in (("measured (s)", 1, "{:.3f}"), ("estimate (s)", 2, "{:.3f}"),
                            ("measured / estimate", 3, "{:.2f}"),
                            ("time per frame (1 000 = 1)", 4, "{:.2f}")):
        assert cells[label] == [fmt.format(r[col]) for r in runs], label
    for frames, measured, estimate, ratio, per_frame in runs:  # consistent, to its rounding
        assert abs(measured / estimate / ratio - 1) < 0.02
        assert abs(measured / frames / (runs[0][1] / runs[0][0]) / per_frame - 1) < 0.02
    load = re.search(r"load ([\d.]+) ", record).group(1)
    assert f"load ≈ {float(load):.1f} on the shared 2-core machine" in text


def test_the_benchmark_still_builds_every_quoted_case(tmp_path: Path) -> None:
    added = [str(ROOT / "benchmarks"), str(ROOT / "tests")]  # the script and its bomb builders
    sys.path[:0] = added
    try:
        import hostile_inputs

        built = hostile_inputs.cases(tmp_path)
    finally:
        for path in added:
            sys.path.remove(path)
    record = _hostile()
    for case, _ in CELLS.values():
        path, _call = built[case]
        assert path.stat().st_size == record[case][0], case


def test_the_fuzz_table_gives_each_test_its_ci_budget() -> None:
    """The "CI examples" column is ``⌈10 × 200 × share⌉`` per ``@budget(share)``, in order."""
    import math

    from hypothesis import settings

    root = Path(__file__).resolve().parents[1]
    doc = (root / "docs" / "reliability.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| .* \| `(test_fuzz_\w+\.py)` \| .* \| ([^|]+) \|$", doc, re.M)
    checked = 0
    for module, cell in rows:
        shares = re.findall(r"@budget\(([\d.]+)\)",
                            (root / "tests" / "fuzz" / module).read_text(encoding="utf-8"))
        if not shares:  # parametrized, not a hypothesis budget (the writers)
            continue
        want = " + ".join(f"{math.ceil(10 * 200 * float(x)):,}".replace(",", " ")
                          for x in shares)
        assert cell.strip() == want, module
        checked += 1
    assert checked >= 12 and settings.get_profile("ci").max_examples == 200
