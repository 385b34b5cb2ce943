"""The accuracy check: compile warns, with the figure, when a motif is far from the reference.

Issue 19, item 9: ``-m rng=time-fft`` on the TI chirps gave many times the conventional
detections without a word.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from backends.reference.accuracy import VALUE_RTOL, NodeAccuracy, check_accuracy
from compiler.compile import compile_graph
from ir import Graph
from radarsnn.cli import main

TI = Path(__file__).resolve().parents[1] / "examples" / "chains" / "ti_range.yaml"


@pytest.fixture(scope="module")
def chirps(shared_data) -> np.ndarray:
    return np.load(shared_data / "ti_chirps" / "data_tum.npy")


def test_exact_default_motifs_pass_and_time_fft_is_flagged(chirps):
    g = Graph.from_yaml(TI)
    good = check_accuracy(compile_graph(g, "loihi2", calibration_inputs={"chirp": chirps}),
                          {"chirp": chirps})
    assert good.warnings() == [] and good.n_frames == 4
    assert {a.node for a in good.nodes} == {"rng", "det"}
    (rng,) = [a for a in good.nodes if a.node == "rng"]
    assert rng.kind == "values" and rng.error < VALUE_RTOL
    bad = check_accuracy(compile_graph(g, "loihi2", motifs={"rng": "time-fft"},
                                       calibration_inputs={"chirp": chirps}), {"chirp": chirps})
    figures = {a.node: a for a in bad.nodes}
    assert figures["rng"].motif == "time-fft" and figures["rng"].large
    assert figures["det"].spiking > 4 * figures["det"].conventional  # the flood of the issue
    assert len(bad.warnings()) == 2 and "% RMS error" in bad.warnings()[0]


def test_the_bounds_by_hand():
    assert not NodeAccuracy("f", "time", "values", error=0.05).large
    assert NodeAccuracy("f", "time", "values", error=0.051).large
    assert not NodeAccuracy("d", "time", "decisions", 0.0, differing=2, conventional=0).large
    assert not NodeAccuracy("d", "time", "decisions", 0.0, differing=5, conventional=20).large
    assert NodeAccuracy("d", "time", "decisions", 0.0, differing=6, conventional=20).large
    line = NodeAccuracy("d", "time", "decisions", 0.1, 49, 51, 6).describe()
    assert line == "node 'd' (motif time): 51 detections where the conventional chain has 6 " \
                   "(49 cells differ)"


def test_compile_prints_the_warning_and_stores_the_figures(chirps, tmp_path, capsys):
    np.save(tmp_path / "chirps.npy", chirps)
    # the unmeasured compile's check on the calibration data (the measured default refuses
    # the S-FFT here: tests/test_accuracy_contract.py)
    argv = ["compile", str(TI), "-c", str(tmp_path / "chirps.npy"), "-q", "--accuracy", "off"]
    assert main([*argv, "-o", str(tmp_path / "good")]) == 0
    assert "warning" not in capsys.readouterr().err
    assert main([*argv, "-o", str(tmp_path / "bad"), "-m", "rng=time-fft", "--json"]) == 0
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert err[0].startswith("warning: node 'rng' (motif time-fft): ")
    assert "on the calibration data (4 frame(s))" in err[0]
    doc = json.loads(captured.out)
    assert [n["node"] for n in doc["accuracy"]["nodes"] if n["large"]] == ["rng", "det"]
    stored = json.loads((tmp_path / "bad" / "program.json").read_text())["extra"]["accuracy"]
    assert stored == doc["accuracy"]
