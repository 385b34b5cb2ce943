"""The demo's spiking chain: compiled for loihi2, simulated, scored, drawn."""

from __future__ import annotations

import json

from compiler.cli import main
from compiler.demo import run_demo


def test_carrada_spiking_demo_finds_the_targets_and_writes_figures(tmp_path):
    report = run_demo(seed=0, presets=["carrada"], out_dir=tmp_path)
    scene = report.scenes[0]
    assert scene.target == "loihi2"
    assert scene.spiking_n_found == scene.n_targets == 4
    # measured: 2 false objects, both in the Tx->Rx leakage's range rows 0-1 (their noise is
    # ~110 dB under the leakage in the same neuron, below one step of T = 256), sensitivity
    # 0.99 and precision 0.99 (before per-neuron gains and calibrated rounding: 0.67 / 1.00)
    assert scene.spiking_n_false <= 2
    assert scene.cell_precision >= 0.97 and scene.cell_sensitivity >= 0.97
    assert scene.sft_rmse < 0.01
    assert scene.resources["cores"] > 0 and scene.resources["neurons"] > 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["cores_carrada.png", "rd_carrada.png", "report_carrada.md",
                     "spikes_carrada.png", "summary.md"]
    assert all((tmp_path / n).stat().st_size > 200 for n in names)
    summary = (tmp_path / "summary.md").read_text()
    assert "![RD maps](rd_carrada.png)" in summary and "spiking: 4/4 targets" in summary
    text = report.to_text()
    assert "spiking (loihi2): found 4/4 targets" in text and "resources on loihi2" in text
    # the real-time fit in seconds, in the printed summary and in summary.md
    assert "s per frame (" in text and "against a frame period of 0.1 s: does NOT fit" in text
    assert "- real time: latency " in summary


def test_demo_json_has_the_spiking_figures(capsys, tmp_path):
    assert main(["demo", "--preset", "carrada", "--json", "--out", str(tmp_path)]) == 0
    doc = json.loads(capsys.readouterr().out)
    scene = doc["scenes"][0]
    assert scene["target"] == "loihi2" and scene["cell_sensitivity"] > 0.5
    assert set(scene["timings_s"]) == {"conventional", "compile", "simulate"}
    assert len(doc["files"]) == 5
