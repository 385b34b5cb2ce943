"""Every figure of docs/performance.md is the output of the command the page names.

Timings depend on the machine, so they are not asserted against a new run. The page quotes
recorded runs instead: the output of ``radarsnn bench --json`` and of
``benchmarks/cfar_speed.py``, kept in ``benchmarks/results/``. These tests check that

* every figure in the page's tables equals that output, to the digits quoted;
* the recorded output is what today's code writes: the same keys, and ratios and frames per
  second that the current ``BenchReport`` computes from the recorded seconds;
* ``benchmarks/cfar_speed.py`` still runs and prints the rows the page names (one repeat).

The page's own session block runs a one-repeat ``radarsnn bench --json`` (tests/test_docs_cli.py).
"""

from __future__ import annotations

import dataclasses
import json
import re
import runpy
from pathlib import Path

import pytest

from radarsnn.bench import BenchReport

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "performance.md"
RESULTS = ROOT / "benchmarks" / "results"
#: The recorded run behind each value column of the bench tables, in column order.
BENCH_RUNS = ("bench_carrada.json", "bench_carrada_rd_oscfar.json",
              "bench_carrada_resonator.json")
#: What the ``met`` cell calls each run when a goal is met by some runs only.
RUN_NAMES = ("preset", "chain file", "resonator")
UNITS = {"ms": 1e3, "s": 1.0, "GB": 1.0, "×": 1.0, "": 1.0}
CELL = re.compile(r"^([0-9][0-9 ]*(?:\.[0-9]+)?)\s*(ms|s|GB|×)?$")


def _record(name: str) -> dict:
    return json.loads((RESULTS / name).read_text(encoding="utf-8"))


def _tables(text: str) -> list[list[list[str]]]:
    """The Markdown tables of ``text``: rows of cells, the header first, no separator row."""
    tables, rows = [], []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(set(c) <= {"-", " ", ":"} for c in cells):
                rows.append(cells)
        elif rows:
            tables.append(rows)
            rows = []
    return tables


def _quoted(cell: str) -> tuple[float, int, float] | None:
    """``(value, decimals, unit factor)`` of a figure cell like ``58.4 ms`` (None for ``—``).

    Examples
    --------
    >>> _quoted("**1.83**"), _quoted("5 220"), _quoted("3.73 s"), _quoted("—")
    ((1.83, 2, 1.0), (5220.0, 0, 1.0), (3.73, 2, 1.0), None)
    """
    cell = cell.replace("*", "").strip()
    if cell == "—":
        return None
    match = CELL.match(cell)
    assert match, f"not a figure: {cell!r}"
    number = match.group(1).replace(" ", "")
    decimals = len(number.split(".")[1]) if "." in number else 0
    return float(number), decimals, UNITS[match.group(2) or ""]


def _recorded(run: dict, key: str) -> float | None:
    group, _, name = key.partition(".")
    return run.get(group, {}).get(name) if name else run.get(group)


def _bench_rows() -> list[tuple[str, list[str]]]:
    """``(json key, value cells)`` of every row of the page's ``--json key`` tables."""
    out = []
    for table in _tables(PAGE.read_text(encoding="utf-8")):
        if len(table[0]) > 1 and table[0][1] == "`--json` key":
            out += [(row[1].strip("`"), row[2:2 + len(BENCH_RUNS)]) for row in table[1:]]
    return out


def test_the_page_quotes_bench_tables() -> None:
    from radarsnn.bench_user import GOALS

    keys = [key for key, _ in _bench_rows()]
    assert {"seconds.closed", "seconds.floor", "ratios.closed_over_floor",
            "ratios.brian2_over_step_range_stage", "peak_rss_gb"} <= set(keys), keys
    user = {"user_path.run_program_first_call", "user_path.run_program_frame",
            "user_path.run_program_frame_planned", "user_path.frames_axis_1_worker",
            "user_path.frames_axis_n_workers", "user_path.frames_axis_n_threads",
            "user_path.compile_accuracy_off", "user_path.compile_accuracy_on", "cpu.user_s",
            "cpu.system_s", "cpu.threads_user_s", "cpu.threads_system_s",
            "user_path_ratios.threads_speedup", "user_path_ratios.host_thread_speedup",
            "user_path_ratios.host_stream_speedup"}
    assert user | {f"user_path_ratios.{k}" for k in GOALS} <= set(keys), keys


def _goal_met(goal: str, values: list[float | None]) -> str:
    """The ``met`` cell of a goal (``≤ 2``, ``≥ 1.7``) over the runs' values (None: not timed).

    Examples
    --------
    >>> _goal_met("≤ 2", [1.5, 2.5, 1.0]), _goal_met("≥ 1.7", [1.8, 1.9, None])
    ('preset, resonator', 'yes')
    >>> _goal_met("≤ 1", [3.0, 2.0, 4.0])
    'no'
    """
    sign, bound = goal.split()
    ok = {name: v <= float(bound) if sign == "≤" else v >= float(bound)
          for name, v in zip(RUN_NAMES, values, strict=True) if v is not None}
    if all(ok.values()):
        return "yes"
    if not any(ok.values()):
        return "no"
    return ", ".join(name for name, met in ok.items() if met)


def test_the_user_path_goals_say_what_the_recorded_runs_met() -> None:
    from radarsnn.bench_user import GOALS

    runs = [_record(name) for name in BENCH_RUNS]
    rows = [t for t in _tables(PAGE.read_text(encoding="utf-8"))
            if t[0][1] == "`--json` key" and t[0][-2:] == ["goal", "met"]]
    seen = set()
    for table in rows:
        for row in table[1:]:
            key = row[1].strip("`")
            if not key.startswith("user_path_ratios."):
                continue
            name = key.partition(".")[2]
            if name not in GOALS:  # a figure that qualifies the others (the host's)
                assert row[-2:] == ["—", "—"], key
                continue
            assert row[-2] == GOALS[name].replace("goal <=", "≤").replace("goal >=", "≥"), key
            values = [r["user_path_ratios"].get(name) for r in runs]
            assert row[-1] == _goal_met(row[-2], values), key
            seen.add(name)
    assert seen == set(GOALS)
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    preset = runs[0]
    assert f"a frames axis of {preset['n_frames_axis']} frames" in text
    assert f"{preset['workers']} workers (the cores available)" in text
    kinds = {r["parallel"] for r in runs}
    assert len(kinds) > 1 or f"(`parallel`: {kinds.pop()} in all three runs)" in text


@pytest.mark.parametrize("key, cells", _bench_rows(), ids=[k for k, _ in _bench_rows()])
def test_every_bench_figure_is_the_recorded_runs(key: str, cells: list[str]) -> None:
    for name, cell in zip(BENCH_RUNS, cells, strict=True):
        value = _recorded(_record(name), key)
        quoted = _quoted(cell)
        if quoted is None:
            assert value is None, f"{key}: {name} has {value}, the page says —"
            continue
        figure, decimals, factor = quoted
        assert value is not None, f"{key}: not in {name}"
        assert abs(value * factor - figure) <= 0.5 * 10.0 ** -decimals + 1e-9, (
            f"{key}: the page says {cell}, {name} has {value}")


def test_the_recorded_runs_are_what_the_bench_writes_today() -> None:
    """Same keys, and the ratios and frames/s the current code computes from its seconds."""
    fields = {f.name for f in dataclasses.fields(BenchReport)}
    for name in BENCH_RUNS:
        run = _record(name)
        report = BenchReport(**{k: tuple(v) if k.startswith("load_") else v
                                for k, v in run.items() if k in fields})
        again = json.loads(json.dumps(report.to_dict()))
        assert set(again) == set(run), name
        assert again["ratios"] == run["ratios"] and again["frames_per_s"] == run["frames_per_s"]


def test_the_run_conditions_and_floor_products_are_the_recorded_ones() -> None:
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    preset, chain, resonator = (_record(name) for name in BENCH_RUNS)
    assert (f"load average was {preset['load_before'][0]:.2f} before and "
            f"{preset['load_after'][0]:.2f} after the preset run, "
            f"{chain['load_before'][0]:.2f} before the chain-file run and "
            f"{resonator['load_before'][0]:.2f} before the resonator run") in text
    assert preset["machine"].split()[-1] in text and f"{preset['cpu_count']}-core" in text
    assert preset["repeats"] == chain["repeats"] == resonator["repeats"] == 5
    assert preset["threads"] == chain["threads"] == resonator["threads"] == 1
    assert resonator["motif"] == "resonator" and chain["chain"] and not preset["chain"]
    assert "radarsnn bench --repeats 5 --step-repeats 3 --json" in text
    for product in preset["floor_products"]:
        assert f"`{product}`" in text
    assert any("spike counts equal the step engine's" in n for n in preset["notes"])


def _cfar_rows(text: str) -> dict[str, list[str]]:
    """Script row label (spaces collapsed) -> its printed columns (old ms, new ms, old/new,
    identical).

    Examples
    --------
    >>> _cfar_rows("case  old ms\\nCA study       (N=176)    49.78     6.33     7.9x  True\\n")
    {'CA study (N=176)': ['49.78', '6.33', '7.9x', 'True']}
    """
    rows = {}
    for line in text.splitlines():
        match = re.match(r"^(.*?)\s+([0-9.]+)\s+([0-9.]+)\s+([0-9.]+x)\s+(True|False)$", line)
        if match:
            rows[" ".join(match.group(1).split())] = list(match.groups()[1:])
    return rows


def test_every_cfar_figure_is_the_recorded_run() -> None:
    recorded_text = (RESULTS / "cfar_speed.txt").read_text(encoding="utf-8")
    recorded = _cfar_rows(recorded_text)
    (table,) = [t for t in _tables(PAGE.read_text(encoding="utf-8")) if t[0][1] == "script row"]
    assert len(table) - 1 == len(recorded) == 6
    for row in table[1:]:
        label = row[1].strip("`")
        old, new, ratio, same = recorded[label]
        assert row[2:] == [f"{old} ms", f"{new} ms", ratio.replace("x", "×")], label
        assert same == "True", label
    before = re.search(r"load average ([0-9.]+)", recorded_text).group(1)
    after = re.search(r"load average after ([0-9.]+)", recorded_text).group(1)
    assert f"load average {before} before, {after} after" in " ".join(
        PAGE.read_text(encoding="utf-8").split())
    assert ", 21 repeats," in recorded_text


def test_the_cfar_script_still_prints_those_rows(capsys) -> None:
    script = runpy.run_path(str(ROOT / "benchmarks" / "cfar_speed.py"))
    script["main"](["--repeats", "1"])
    printed = _cfar_rows(capsys.readouterr().out)
    recorded = _cfar_rows((RESULTS / "cfar_speed.txt").read_text(encoding="utf-8"))
    assert list(printed) == list(recorded)
    assert all(columns[-1] == "True" for columns in printed.values())
