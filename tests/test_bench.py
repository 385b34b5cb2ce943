"""``radarsnn bench`` runs and reports its figures (timings are not asserted: benchmarks/)."""

from __future__ import annotations

import json

from compiler.bench import BenchReport, run_bench
from compiler.cli import main


def test_bench_times_the_closed_form_against_numpy():
    report = run_bench("seed003", repeats=1, modes=("closed",), brian2=False)
    assert set(report.seconds) == {"conventional", "closed"}
    assert report.ratios()["closed_over_conventional"] > 0
    assert "closed" in report.to_text() and report.peak_rss_gb > 0


def test_ratios_are_computed_from_one_run():
    r = BenchReport(preset="p", repeats=1, threads=1, machine="m",
                    seconds={"conventional": 0.1, "closed": 0.5, "closed_range_stage": 0.01,
                             "step_range_stage": 0.1, "brian2_range_stage": 2.0})
    assert r.ratios() == {"closed_over_conventional": 5.0,
                          "brian2_over_closed_range_stage": 200.0,
                          "brian2_over_step_range_stage": 20.0}
    assert r.frames_per_s["closed"] == 2.0


def test_bench_cli_json(capsys):
    assert main(["bench", "--preset", "seed003", "--repeats", "1", "--mode", "closed",
                 "--no-brian2", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["preset"] == "seed003" and "closed" in doc["frames_per_s"]
