"""The command line and the demo: exit codes, messages, and the demo's detections."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from compiler.chains import range_doppler_chain
from ir.errors import RadarSNNError
from radar.config import preset
from radarsnn.cli import main
from radarsnn.demo import run_demo

CHAINS = Path(__file__).resolve().parents[1] / "examples" / "chains"


@pytest.mark.parametrize("name", ["seed003", "carrada"])
def test_demo_finds_every_target_without_false_alarms(name):
    scene = run_demo(seed=0, presets=[name], spiking=False).scenes[0]
    assert scene.n_found == scene.n_targets
    assert scene.n_false == 0


def test_demo_prints_a_table_and_json(capsys):
    assert main(["demo", "--preset", "carrada", "--conventional-only", "--no-figures"]) == 0
    out = capsys.readouterr().out
    assert "found 4/4 targets" in out and "aliased Doppler" in out
    # no spiking chain ran: nothing about it (was "spiking MISSED" and "found 0/4")
    assert "MISSED" not in out and "spiking (" not in out and "0/4" not in out
    assert main(["demo", "--preset", "carrada", "--json", "--conventional-only",
                 "--no-figures"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["scenes"][0]["preset"] == "carrada" and doc["scenes"][0]["target"] is None
    # the map's shape in the axis order of the chain's arrays ([doppler, range]), named
    scene = doc["scenes"][0]
    assert scene["map_axes"] == ["doppler", "range"] and scene["map_shape"] == [64, 256]
    assert "RD map 64 x 256 (doppler x range)" in out


def test_a_conventional_only_summary_does_not_report_a_spiking_chain(tmp_path):
    run_demo(seed=0, presets=["carrada"], spiking=False, out_dir=tmp_path)
    text = (tmp_path / "summary.md").read_text(encoding="utf-8")
    assert "missed" not in text and "- spiking:" not in text and "not run" in text
    assert "found 4/4" not in text and "4/4 targets" in text


def test_validate_accepts_the_examples(capsys):
    paths = sorted(str(p) for p in CHAINS.glob("*.yaml"))
    assert len(paths) >= 3
    assert main(["validate", *paths]) == 0
    assert "is valid" in capsys.readouterr().out


def test_validate_names_the_bad_node(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nnodes:\n  - {id: a, op: input, shape: {range: 8}}\n"
                   "  - {id: w, op: window, input: a, axis: doppler, kind: hann}\n"
                   "  - {id: o, op: output, input: w}\n")
    assert main(["validate", str(bad)]) != 0
    err = capsys.readouterr().err
    assert err.startswith("error:") and "'w'" in err and "doppler" in err


def test_validate_reports_a_missing_file(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope.yaml")]) != 0
    assert "nope.yaml" in capsys.readouterr().err


def test_schema_is_json_with_every_op(tmp_path):
    out = tmp_path / "schema.json"
    assert main(["schema", "-o", str(out)]) == 0
    text = out.read_text()
    for op in ("adc_input", "window", "dft", "cfar", "magnitude", "sum", "output"):
        assert f'"{op}"' in text
    json.loads(text)


def test_chain_factory_windows_doppler_on_request():
    config = preset("carrada")
    with_window = range_doppler_chain(config)
    without = range_doppler_chain(config, doppler_window=None)
    assert "dwin" in with_window.topological_order()
    assert "dwin" not in without.topological_order()
    assert with_window.infer_types()["det"].axes == without.infer_types()["det"].axes


def test_run_reads_an_artifact(tmp_path, capsys):
    from backends import save
    from compiler.snn import (
        Decoder,
        Encoder,
        LatencyCode,
        MatrixProjection,
        NeuronParams,
        Population,
        SpikingNetwork,
    )

    net = SpikingNetwork(
        name="tiny", n_steps=8,
        populations=[Population(id="in", shape={"i": 2}, source=True),
                     Population(id="out", shape={"o": 1},
                                params=NeuronParams(v_th=2.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1)))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="y", population="out", kind="spiked")])
    save(net, tmp_path / "art")
    np.save(tmp_path / "x.npy", np.array([1.0, 1.0]))
    assert main(["run", str(tmp_path / "art"), "--input", str(tmp_path / "x.npy"),
                 "--mode", "step", "--json", "-o", str(tmp_path / "y.npz")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["spike_counts"]["out"] == 1
    assert np.load(tmp_path / "y.npz")["y"].tolist() == [1.0]
    assert main(["run", str(tmp_path / "missing"), "--input", str(tmp_path / "x.npy")]) == 1


def test_a_closed_pipe_ends_the_command_quietly(monkeypatch, capsys):
    """`radarsnn schema | head` used to end with "error: [Errno 32] Broken pipe", exit 2."""
    import sys

    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert main(["schema"]) == 0
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert "Broken pipe" not in err and "error" not in err


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_is_accepted_before_and_after_the_command(tmp_path, capsys, where):
    """Issue 19 item 8: ``radarsnn validate X --debug`` was refused ('unrecognized arguments')."""
    missing = str(tmp_path / "missing.yaml")
    argv = ["--debug", "validate", missing] if where == "before" else ["validate", missing,
                                                                        "--debug"]
    with pytest.raises(RadarSNNError, match="cannot read the chain file"):
        main(argv)
    assert main(["validate", missing]) != 0  # without it: the one-line error
    assert capsys.readouterr().err.startswith("error: ")
