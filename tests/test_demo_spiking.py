"""The demo's spiking chain: compiled measured (as a user's compile), simulated, scored, drawn."""

from __future__ import annotations

import json

import pytest

from radarsnn.cli import build_parser
from radarsnn.demo import DEFAULT_TARGET, DemoReport, SceneReport, run_demo


@pytest.fixture(scope="module")
def carrada(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    return run_demo(seed=0, presets=["carrada"], out_dir=out), out


def test_carrada_spiking_demo_is_the_measured_compile_and_finds_the_targets(carrada):
    report, out = carrada
    scene = report.scenes[0]
    assert scene.target == DEFAULT_TARGET == "kapoho_point" and scene.refused is None
    # what radarsnn.compile_graph chooses on the held-back calibration frame: the resonator
    # DFTs (the S-FT's 263 269 steps per frame miss 10 frames/s), the spiking OS-CFAR
    assert scene.motifs == {"rng__moving": "resonator", "dop__moving": "resonator",
                            "det": "time"}
    assert scene.accuracy[0] == "accuracy on 1 held-out frame(s)"
    assert [line.split()[:2] for line in scene.accuracy[1:]] == [
        ["ok", "rng__moving"], ["ok", "dop__moving"], ["ok", "det"]]
    assert scene.spiking_n_found == scene.n_targets == 4 and scene.spiking_n_false == 0
    assert scene.cell_precision >= 0.97 and scene.cell_sensitivity >= 0.97
    assert scene.sft_rmse < 0.01
    assert scene.resources["cores"] > 0 and scene.resources["latency_fits"] is True
    names = sorted(p.name for p in out.iterdir())
    assert names == ["cores_carrada.png", "rd_carrada.png", "report_carrada.md",
                     "spikes_carrada.png", "summary.md"]
    assert all((out / n).stat().st_size > 200 for n in names)
    summary = (out / "summary.md").read_text()
    assert "![RD maps](rd_carrada.png)" in summary and "spiking: 4/4 targets" in summary
    assert "- compiled measured (motifs `rng__moving=resonator`" in summary
    text = report.to_text()
    assert "spiking (kapoho_point): found 4/4 targets" in text
    assert "    ok    det [time]: sensitivity" in text  # the compile's per-stage lines
    assert "s per frame (422 steps" in text and "against a frame period of 0.1 s: fits" in text
    assert "- real time: latency " in summary
    doc = json.loads(report.to_json())  # what `radarsnn demo --json` prints
    (scene_doc,) = doc["scenes"]
    assert scene_doc["accuracy"] == scene.accuracy and scene_doc["refused"] is None
    assert set(scene_doc["timings_s"]) == {"conventional", "compile", "simulate"}
    assert len(doc["files"]) == 5


def test_the_cli_demo_defaults_to_the_board_and_takes_another_target():
    args = build_parser().parse_args(["demo"])
    assert args.target == DEFAULT_TARGET
    assert build_parser().parse_args(["demo", "-t", "loihi2"]).target == "loihi2"


def test_a_refused_compile_is_shown_with_the_compilers_message_and_no_spiking_figures():
    # carrada on one loihi2 chip (measured: the resonator chain's Doppler stage needs
    # 2048 multiplexed repetitions x 65 steps, 1.33 s per 0.1 s frame)
    why = ("no spiking configuration that keeps the accuracy contract fits the frame deadline: "
           "... network 'carrada-rd-cfar#1' (stage 'dop') alone runs 2048 ...")
    scene = SceneReport(preset="carrada", chain="carrada-rd-cfar", map_shape=(64, 256),
                        targets=[], n_peaks=3, n_clutter=3, n_false=0, seconds=1.0,
                        target="loihi2", refused=why, timings_s={"compile": 1.0})
    report = DemoReport(seed=0, scenes=[scene])
    text, md = report.to_text(), report.to_markdown()
    assert f"spiking (loihi2): refused by the compiler: {why}" in text
    assert "spiking (loihi2): found" not in text and "resources on" not in text
    assert f"- spiking: refused by the compiler: {why}" in md and "spikes_carrada" not in md
