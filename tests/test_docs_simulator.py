"""The performance notes of docs/simulator.md are the recorded output of
``python benchmarks/simulator.py --repeats 7`` (``benchmarks/results/simulator.txt``).

The run takes over a minute (and Brian2's cython target a C compiler), so the test compares the
page with the record, figure by figure; timings are never asserted against a new run.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "simulator.md"
RECORD = ROOT / "benchmarks" / "results" / "simulator.txt"


def _spaced(n: int) -> str:
    return f"{n:,}".replace(",", " ")


def test_the_performance_notes_are_the_recorded_run() -> None:
    record = RECORD.read_text(encoding="utf-8")
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    for engine in ("step", "closed"):
        built, reused = re.search(rf"^ours {engine}\s*:\s+([\d.]+) ms plan built in the call,\s+"
                                  r"([\d.]+) ms plan reused", record, re.M).groups()
        assert f"| {engine} | {built} ms | {reused} ms |" in text, engine
    net = re.search(r"^network: (\d+) chirps x (\d+) samples -> (\d+) neurons, (\d+) stored "
                    r"synapses \((\d+) instances\), (\d+) steps", record, re.M).groups()
    chirps, samples, neurons, stored, instances, steps = (int(v) for v in net)
    assert (f"the {samples}-point time-coded S-FT × {chirps} chirps ({_spaced(neurons)} neurons, "
            f"{steps} steps, {instances / 1e6:.2f} M synapse instances from one shared "
            f"{_spaced(stored)}-entry matrix)") in text
    b2 = {m.group(1): m.groups()[1:] for m in re.finditer(
        r"^brian2 (\w+): build ([\d.]+) s, run ([\d.]+) s", record, re.M)}
    assert (f"numpy target build {b2['numpy'][0]} s + run {b2['numpy'][1]} s, cython target "
            f"build {b2['cython'][0]} s + run {b2['cython'][1]} s") in text
    assert record.count("spike-step agreement with ours: 100.0000%") == 2
    ratios = {m.group(1): [float(v) for v in m.groups()[1:]] for m in re.finditer(
        r"^  (\w+, plan \w+)\s+([\d.]+)x \(goal met\)\s+[\d.]+x\s+[\d.]+x\s+([\d.]+)x \(goal met\)",
        record, re.M)}
    assert len(ratios) == 4 and "not met" not in record
    closed = [v for k, vs in ratios.items() if k.startswith("closed") for v in vs]
    step = [v for k, vs in ratios.items() if k.startswith("step") for v in vs]
    assert (f"Brian2's run takes {min(closed)}× (numpy, against our closed form with the plan "
            f"built in the call) to {max(closed)}× (cython, plan reused)") in text
    assert ratios["closed, plan built"][0] == min(closed)
    assert ratios["closed, plan reused"][1] == max(closed)
    assert f"and {min(step)}× to {max(step)}× the step engine's" in text
    mib, times, ours = re.search(r"([\d.]+) MiB synapse arrays = (\d+)x our weight storage",
                                 record).groups() + (
        re.search(r"our weight storage \(plan\): ([\d.]+) MiB", record).group(1),)
    assert f"{mib} MiB of synapse arrays ({times}× our plan's {ours} MiB)" in text
    load = float(re.search(r"^before: load average ([\d.]+)", record, re.M).group(1))
    assert f"load ≈ {load:.1f};" in text
