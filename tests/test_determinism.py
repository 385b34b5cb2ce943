"""Determinism: the same chain + options + seed gives byte-identical artifacts, reports and
outputs in two fresh interpreters (hash randomisation differs between them)."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = r"""
import hashlib, io, json, sys
from pathlib import Path

import numpy as np

from backends import load, save
from backends.reference import run_program
from compiler.calibration import synthetic_inputs
from compiler.compile import compile_graph
from ir import Graph

out = Path(sys.argv[1])
graph = Graph.from_yaml('''
name: determinism
nodes:
  - {id: adc, op: adc_input, shape: {chirp: 4, sample: 16}, complex: true}
  - {id: win, op: window, input: adc, axis: sample, kind: hann}
  - {id: rng, op: dft, input: win, axis: sample, out_axis: range}
  - {id: mag, op: magnitude, input: rng, kind: square}
  - {id: rd, op: sum, input: mag, axis: chirp}
  - {id: det, op: cfar, input: rd, kind: os, guard: 1, train: 2, k: 3, alpha: 1.5}
  - {id: out, op: output, input: det}
''')
x = synthetic_inputs(graph, seed=7)
program = compile_graph(graph, target="loihi2", calibration_inputs=x,
                        options={"headroom": 1.25})
save(program, out / "artifact")
result = run_program(load(out / "artifact"), x, out_of_range="clip")
buf = io.BytesIO()
np.savez(buf, **{k: np.asarray(v) for k, v in sorted(result.values.items())})
(out / "outputs.npz").write_bytes(buf.getvalue())
(out / "report.json").write_text(program.records["report"].to_json())
(out / "counts.json").write_text(json.dumps({"spikes": result.spike_counts,
                                             "events": result.synaptic_events,
                                             "clipped": result.clipped}, sort_keys=True))
"""


def _digests(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_two_fresh_interpreters_write_identical_bytes(tmp_path):
    runs = []
    for seed in ("1", "2"):  # different hash seeds: no dict/set order may leak into bytes
        folder = tmp_path / f"run{seed}"
        folder.mkdir()
        env = {**os.environ, "PYTHONHASHSEED": seed}
        done = subprocess.run([sys.executable, "-c", SCRIPT, str(folder)], cwd=ROOT, env=env,
                              capture_output=True, text=True, timeout=300, check=False)
        assert done.returncode == 0, done.stderr
        runs.append(_digests(folder))
    first, second = runs
    assert sorted(first) == sorted(second)
    assert {"artifact/program.json", "artifact/report.md", "outputs.npz", "report.json",
            "counts.json"} <= set(first)
    assert any(k.startswith("artifact/networks/") for k in first)
    different = [k for k in first if first[k] != second[k]]
    assert not different, f"files differ between fresh runs: {different}"
    counts = json.loads((tmp_path / "run1" / "counts.json").read_text())
    assert sum(counts["spikes"].values()) > 0
