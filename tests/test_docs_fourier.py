"""The figures of docs/fourier.md's S-FT, magnitude, range-Doppler and S-FFT tables are the
recorded output of ``python benchmarks/fourier.py --study time-coded --study fft``
(``benchmarks/results/fourier.txt``), digit for digit.

The run compiles and simulates dozens of networks (over a minute), so the tests compare the page
with the record; the last one checks that the benchmark still prints those lines (its source).
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "fourier.md"
RECORD = ROOT / "benchmarks" / "results" / "fourier.txt"


def _table(head: str) -> list[list[str]]:
    """The body rows (cells, ``*`` removed; ``\\|`` is no separator) of the page's table whose
    header starts ``head``."""
    text = PAGE.read_text(encoding="utf-8")
    lines = text[text.index(head):].split("\n\n")[0].splitlines()[2:]
    return [[c.strip().replace("*", "") for c in re.split(r"(?<!\\)\|", line.strip()[1:-1])]
            for line in lines]


def _record() -> str:
    return RECORD.read_text(encoding="utf-8")


def _spaced(n: int) -> str:
    return f"{n:,}".replace(",", " ")


def test_the_ti_rmse_table_is_the_recorded_one() -> None:
    record, expected = _record(), []
    for n in (256, 1024):
        block = record.split(f"N = {n} ")[1].split("\n\n")[0]
        for policy in ("static", "per-input"):
            auto = re.search(rf"^\s*{policy} auto\s+(.+?)\s+\(auto picked: (K+)", block, re.M)
            for schedule, name in (("constant", "constant"), ("companding", "companding (= auto)")):
                values = re.search(rf"^\s*{policy} {schedule}\s+(.+)$", block, re.M).group(1)
                if schedule == "companding":
                    assert auto.group(1).split() == values.split()  # auto picked companding
                expected.append([str(n), policy, name, *values.split()])
    assert _table("| N | policy | schedule | T=32 |") == expected
    static_256 = {int(r[0]): float(r[6]) for r in expected if r[1] == "static"
                  and r[2] == "constant"}
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert (f"misses them at T = 256 ({static_256[256]:.5f} / {static_256[1024]:.5f} static)"
            in text)
    at_256 = {(r[0], r[1]): float(r[6]) for r in expected if r[2] != "constant"}
    assert all(v <= (0.005 if p == "static" else 0.0025) for (_, p), v in at_256.items())
    assert "static ≤ 0.005, per-input ≤ 0.0025 — met by the default" in text


def test_the_magnitude_table_is_the_recorded_one() -> None:
    record = _record()
    errors = {m.group(1): f"{m.group(2)} / {m.group(3)}" for m in re.finditer(
        r"^\s+(\w+) \(TI N=256, T=256, .*?= ([\d.]+), RMS = ([\d.]+)$", record, re.M)}
    ratios = {m.group(1): f"[{m.group(2)}, {m.group(3)}]" for m in re.finditer(
        r"^\s+(\w+): ratio to \|z\| in \[([\d.]+), ([\d.]+)\]", record, re.M)}
    rows = {r[0].strip("`"): r for r in _table("| motif | computes | ratio to")}
    assert rows["host"][3] == f"{errors['host']} (S-FT error only)"
    for motif in ("l1", "amb"):
        assert rows[motif][2:] == [ratios[motif], errors[motif]], motif


def test_the_range_doppler_table_is_the_recorded_one() -> None:
    recorded = [list(m.groups()) for m in re.finditer(
        r"^\s+(\w+) T=(\d+)\s+(\w+): peak bin equal (\d+/\d+), within 1 bin (\d+/\d+), "
        r"max \|normalised map error\| ([\d.]+)", _record(), re.M)]
    assert len(recorded) == 18
    assert _table("| preset | T | magnitude | same bin |") == recorded


def test_the_sfft_tables_are_the_recorded_ones() -> None:
    record = _record()
    rows = _table("| N | radices | neurons (+1 clock) |")
    counted = list(re.finditer(
        r"^N=(\d+) radices \(([\d, ]+)\): compiled per instance (\d+) neurons \(\+1 clock\), "
        r"(\d+) butterfly synapses \(per layer \[([\d, ]+)\].*?\+ (\d+) offset synapses, "
        r"(\d+) steps; estimate (\d+), (\d+), (\d+)$", record, re.M))
    assert len(rows) == len(counted) == 3
    for row, m in zip(rows, counted, strict=True):
        n, radices, neurons, total, layers, offsets, steps, *estimate = m.groups()
        per_layer = ", ".join(_spaced(int(v)) for v in layers.split(", "))
        assert row == [n, radices.replace(" ", ""), _spaced(int(neurons)),
                       f"{per_layer} (Σ {_spaced(int(total))})", _spaced(int(offsets)), steps,
                       ", ".join(_spaced(int(v)) for v in estimate)], n
    accuracy = [list(m.groups()) for m in re.finditer(
        r"^\s+(\d+)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+True$", record, re.M)]
    assert len(accuracy) == 6
    assert _table("| N | T | S-FFT | dense S-FT") == accuracy
    assert max(float(r[4]) for r in accuracy) < 1.5  # "within 1.5× of the dense S-FT"
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert "within 1.5× of the dense S-FT" in text
    const = {r[0]: float(r[6]) for r in _table("| N | policy | schedule | T=32 |")
             if r[1] == "static" and r[2] == "constant"}
    sfft = {r[0]: float(r[2]) for r in accuracy if r[1] == "256"}
    low, high = sorted(round(sfft[n] / const[n], 1) for n in ("256", "1024"))
    assert f"N = 1024, T = 256, static: the S-FFT is {low}–{high}× that." in text
    assert re.search(r"Table 3: 4 608, 37 888, 550\)$", record, re.M)


def test_the_benchmark_still_prints_those_lines() -> None:
    source = (ROOT / "benchmarks" / "fourier.py").read_text(encoding="utf-8")
    for piece in ("auto picked", "ratio to |z| in", "max |err|/max|z|", "peak bin equal",
                  "within 1 bin", "compiled per instance", "offset synapses", "closed==step",
                  '"time-coded": time_coded_study', '"fft": fft_study'):
        assert piece in source, piece


def test_the_rate_table_is_the_recorded_one() -> None:
    """``python benchmarks/fourier.py --study rate`` (``fourier_rate.txt``, minutes)."""
    record = (RECORD.parent / "fourier_rate.txt").read_text(encoding="utf-8")
    recorded = [[form, _spaced(int(steps)), rmse, f"{secs} s", f"{rss} GB"]
                for form, steps, rmse, limit, secs, rss in re.findall(
                    r"^\s+(1D|2D)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)$",
                    record, re.M)]
    assert len(recorded) == 6
    assert _table("| form | steps | RMSE | sim time | peak RSS |") == recorded
    limits = {"1D": 0.0056, "2D": 0.0060}
    assert all(float(r[2]) <= limits[r[0]] for r in recorded)  # "from 100 steps on"
    assert "(paper: 0.0056 1D, 0.0060 2D at" in PAGE.read_text(encoding="utf-8")
    assert "RMSE 0.0056 (1D), 0.0060 (2D) at 10 000 steps" in record


def _md_rows(record: str, head: str) -> list[list[str]]:
    lines = record[record.index(head):].split("\n\n")[0].splitlines()[2:]
    return [[c.strip() for c in line.strip()[1:-1].split("|")] for line in lines]


def test_the_resonator_tables_are_the_recorded_ones() -> None:
    """``python benchmarks/resonator_accuracy.py`` (``resonator_accuracy.txt``, a minute)."""
    record = (RECORD.parent / "resonator_accuracy.txt").read_text(encoding="utf-8")
    ti = _md_rows(record, "| target | motif | read-out |")
    page = [[c.replace(" (default)", "") for c in row]
            for row in _table("| target | motif | read-out | steps |")]
    assert page == ti
    drift = _md_rows(record, "| coef bits | renorm |")
    rows = _table("| coef bits | renorm | drift bound |")
    assert len(rows) == len(drift) == 12
    for row, rec in zip(rows, drift, strict=True):
        assert row[0].split()[0] == rec[0].split()[0]
        assert row[1] == rec[1].replace(": none", "")
        assert row[2:] == rec[2:], rec[0]
    loihi2 = {(r[1], r[2]): r for r in ti if r[0] == "loihi2"}
    sft_graded, res_graded = loihi2[("time (S-FT)", "T=1024")], loihi2[("resonator", "graded")]
    sft_256, res_256 = loihi2[("time (S-FT)", "T=1279")], loihi2[("resonator", "time T=256")]
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert (f"on loihi2 |X| RMSE {res_graded[5]} against {sft_graded[5]} (graded) and "
            f"{res_256[5]} against {sft_256[5]} (T = 256), Re/Im RMSE {res_graded[6]} against "
            f"{sft_graded[6]} and {res_256[6]} against {sft_256[6]}") in text
    fewer = sorted(int(loihi2[k][4]) / int(res_graded[4]) for k in loihi2 if k[0] != "resonator")
    assert round(fewer[0], -1) == round(fewer[-1], -1) == 270  # "with 270× fewer synapses"
    assert "with 270× fewer synapses" in text


def test_the_carrada_resonator_table_is_the_recorded_one() -> None:
    """``python benchmarks/resonator_carrada.py --seeds 0 1 2 3 4`` (``resonator_carrada.txt``)."""
    record = (RECORD.parent / "resonator_carrada.txt").read_text(encoding="utf-8")
    assert "seeds [0, 1, 2, 3, 4], calibrated on seed 1000" in record
    rows = _md_rows(record, "| motif | sensitivity |")
    assert _table("| motif | sensitivity | precision |") == [[c.replace("*", "") for c in r]
                                                            for r in rows]
    sft, res = rows[0], rows[1]
    n = [int(c.replace(",", "")) for c in (sft[4], res[4], sft[5], res[5], sft[6], res[6])]
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert (f"synapses {n[0] / n[1]:.0f}× fewer in total ({n[0] / 1e6:.1f} M / {n[1] / 1e6:.1f} M)"
            f" and {n[2] / n[3]:.0f}× fewer in the two DFT stages ({n[2] / 1e6:.1f} M / "
            f"{n[3] / 1e6:.2f} M); latency per frame {n[5]} instead of {_spaced(n[4])} steps "
            f"({float(res[7]) * 1e3:.1f} ms instead of {float(sft[7]):.2f} s") in text
    assert float(res[1]) > float(sft[1]) and float(res[2]) > float(sft[2])


def test_the_drift_figures_in_the_prose_are_the_recorded_ones() -> None:
    record = (RECORD.parent / "resonator_accuracy.txt").read_text(encoding="utf-8")
    drift = {(r[0].split()[0], r[1].split(":")[0]): r
             for r in _md_rows(record, "| coef bits | renorm |")}
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    off12, on12, off16 = drift[("12", "off")], drift[("12", "auto")], drift[("16", "off")]
    assert f"it grows with `N`: {float(off12[3]):.2f} at `N = 1024`" in text
    assert (f"`M = 32`, weight error **{on12[3]}** instead of {float(off12[3]):.3f} — better than "
            f"16-bit coefficients without it ({off16[3]}; table below)") in text
    assert on12[1] == "auto: every 32"
    off8, on8 = drift[("8", "off")], drift[("8", "auto")]
    assert (f"would drift by {float(off8[2]) * 100:.0f} % at `N = 1024` without renormalisation, "
            f"{float(on8[2]) * 100:.0f} % with it") in text
    assert (f"drifts each bin by up to {float(off12[4]) * 100:.0f} % ({float(off12[5]):.1f} rad of "
            f"phase) over N = 1024 steps and the magnitude error is {float(off12[6]):.4f}") in text
    head = _record().splitlines()[1]
    assert head == "paper / authors' code at T=256: 0.0108 (N=256), 0.0149 (N=1024)"
    assert "the authors' code gives ≈ 0.0108 (N=256) and 0.0149 (N=1024)" in text
