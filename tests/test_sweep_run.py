"""Running sweeps: results, resumption after a kill, determinism over workers, the CLI function.

A tiny chain (a 16 x 8 dB map -> 2-D OS-CFAR) on a folder of seeded maps keeps every
run to a fraction of a second on the synchronous path; one test starts a real
LocalCluster of processes.
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
import yaml

from ir.errors import CompileError, IRError, RadarConfigError
from radarsnn.cli.sweep import add_parsers
from radarsnn.sweep import run_sweep
from radarsnn.sweep.results import RESULTS_FILE, read_records
from radarsnn.sweep.run import plan_cells
from radarsnn.sweep.spec import parse_spec

CHAIN = {"name": "tiny-os", "nodes": [
    {"id": "rd", "op": "input", "shape": {"range": 16, "doppler": 8}, "domain": "db"},
    {"id": "det", "op": "cfar", "input": "rd", "kind": "os", "axes": ["range", "doppler"],
     "guard": [1, 1], "train": [2, 1], "k": 20, "alpha": 1.1, "edge": ["clip", "wrap"]},
    {"id": "out", "op": "output", "input": "det"}]}


@pytest.fixture
def maps(tmp_path):
    """Nine seeded 16 x 8 'dB maps' with a few bright cells (the last two calibrate).

    The spec's ``cfar_quantiles: [0, 1]`` makes the code span the calibration maps' whole
    range, so no scored value is out of the encoder's range whatever the simulator's policy.
    """
    rng = np.random.default_rng(5)
    folder = tmp_path / "maps"
    folder.mkdir()
    for i in range(9):
        m = rng.normal(50.0, 3.0, (16, 8))
        m[rng.integers(0, 16, 3), rng.integers(0, 8, 3)] += 25.0
        if i >= 7:  # calibration maps: their full range covers every scored value
            m[0, 0] = 100.0
        np.save(folder / f"map{i:02d}.npy", m)
    return folder


def _spec(folder, **over):
    data = {"name": "tiny", "chains": {"os": CHAIN}, "base_dir": str(folder.parent),
            "grid": {"time_steps": [8, 32], "motifs": [{}, {"cfar": "host"}]},
            "options": {"cfar_quantiles": [0.0, 1.0]},
            "frames": {"source": "folder", "path": folder.name, "calibration_frames": 2,
                       "frames_per_cell": 3},
            "metrics": [{"name": "cfar"}], "figures": ["fig7", "pareto"]}
    return parse_spec({**data, **over})


def _records(out):
    """Cell records without their timing, in cell-id order."""
    recs = [{k: v for k, v in r.items() if k not in ("seconds", "cpu_seconds")}
            for r in read_records(out / RESULTS_FILE)]
    return sorted(recs, key=lambda r: r["cell"])


def test_sync_run_writes_results_summary_and_figures(maps, tmp_path):
    out = tmp_path / "out"
    res = run_sweep(_spec(maps), out, scheduler="sync", quiet=True)
    assert (res.n_cells, res.n_run, res.n_skipped, res.n_failed) == (12, 12, 0, 0)
    assert len(read_records(out / RESULTS_FILE)) == 12
    rows = {(r["params"]["time_steps"], json.dumps(r["params"]["motifs"])): r for r in res.rows}
    host = rows[(8, '{"cfar": "host"}')]
    # the host motif is the conventional CFAR itself: exact agreement, and no neurons
    assert host["metrics"]["cfar"]["sensitivity"] == host["metrics"]["cfar"]["precision"] == 1.0
    assert host["metrics"]["cfar"]["fp"] == host["metrics"]["cfar"]["fn"] == 0
    assert host["cost"]["neurons"] == 0 and host["cost"]["frames"] == 7
    spiking = rows[(32, "{}")]
    assert spiking["cost"]["neurons"] == 16 * 8 and spiking["cost"]["steps"] == 32
    assert spiking["metrics"]["cfar"]["tp"] + spiking["metrics"]["cfar"]["fn"] == (
        host["metrics"]["cfar"]["tp"])
    assert spiking["cost"]["spikes_per_frame"] > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary == json.loads(json.dumps(res.rows))
    assert (out / "summary.csv").read_text().splitlines()[0].startswith("point,chain,")
    assert sorted(p.name for p in res.figures) == ["fig7.png", "pareto.png"]
    assert all(p.stat().st_size > 1000 for p in res.figures)


def test_killed_run_resumes_to_the_same_results(maps, tmp_path):
    whole, parts = tmp_path / "whole", tmp_path / "parts"
    run_sweep(_spec(maps), whole, scheduler="sync", quiet=True, figures=False)
    first = run_sweep(_spec(maps), parts, scheduler="sync", quiet=True, figures=False,
                      max_cells=5)
    assert first.n_run == 5 and sum(r["complete"] for r in first.rows) < 4
    with (parts / RESULTS_FILE).open("a") as f:  # killed while writing a record
        f.write('{"cell": "torn", "metr')
    second = run_sweep(_spec(maps), parts, scheduler="sync", quiet=True, figures=False)
    assert (second.n_run, second.n_skipped) == (7, 5)
    assert _records(parts) == _records(whole)
    again = run_sweep(_spec(maps), parts, scheduler="sync", quiet=True, figures=False)
    assert (again.n_run, again.n_skipped) == (0, 12)
    assert json.loads((parts / "summary.json").read_text()) == json.loads(
        (whole / "summary.json").read_text())


def test_changing_a_point_recomputes_only_its_cells(maps, tmp_path):
    out = tmp_path / "out"
    run_sweep(_spec(maps), out, scheduler="sync", quiet=True, figures=False)
    grown = _spec(maps, grid={"time_steps": [8, 32, 64], "motifs": [{}, {"cfar": "host"}]})
    res = run_sweep(grown, out, scheduler="sync", quiet=True, figures=False)
    assert (res.n_run, res.n_skipped) == (6, 12)


def test_point_ids_hash_what_decides_the_result(maps):
    base = [p["point"] for p in plan_cells(_spec(maps))]
    assert len(set(base)) == 4 and base == [p["point"] for p in plan_cells(_spec(maps))]
    for over in ({"out_of_range": "reject"}, {"mode": "closed"},
                 {"metrics": [{"name": "cfar", "label": "c2"}]},
                 {"options": {"cfar_quantiles": [0.0, 0.99]}}):
        assert not set(base) & {p["point"] for p in plan_cells(_spec(maps, **over))}, over
    more = _spec(maps, frames={"source": "folder", "path": maps.name, "calibration_frames": 2,
                               "frames_per_cell": 3, "n_frames": 3})
    assert [p["point"] for p in plan_cells(more)] == base  # fewer frames: same points


def test_threaded_cluster_1_and_2_workers_identical(maps, tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    run_sweep(_spec(maps), one, workers=1, processes=False, quiet=True, figures=False)
    run_sweep(_spec(maps), two, workers=2, processes=False, quiet=True, figures=False)
    run_sweep(_spec(maps), tmp_path / "sync", scheduler="sync", quiet=True, figures=False)
    assert _records(one) == _records(two) == _records(tmp_path / "sync")
    assert (one / "summary.json").read_bytes() == (two / "summary.json").read_bytes()


def test_local_cluster_of_processes(maps, tmp_path):
    out = tmp_path / "proc"
    res = run_sweep(_spec(maps), out, workers=2, quiet=True, figures=False)
    run_sweep(_spec(maps), tmp_path / "sync", scheduler="sync", quiet=True, figures=False)
    assert res.n_run == 12 and _records(out) == _records(tmp_path / "sync")


def test_compile_failures_are_recorded_per_cell(maps, tmp_path):
    spec = _spec(maps, grid={"time_steps": [8], "motifs": [{"cfar": "warp"}]})
    res = run_sweep(spec, tmp_path / "out", scheduler="sync", quiet=True, figures=False)
    assert res.n_failed == 3 and res.rows[0]["error"].startswith("CompileError")
    assert "warp" in res.rows[0]["error"] and res.rows[0]["metrics"] == {}
    assert res.rows[0]["complete"] and res.figures == []
    np.save(maps / "map99.npy", np.zeros((4, 4)))  # a calibration map of the wrong shape
    res = run_sweep(_spec(maps, grid={"time_steps": [8]}), tmp_path / "o2", scheduler="sync",
                    quiet=True, figures=False)
    assert res.n_failed == 3 and "input 'rd': array shape (4, 4)" in res.rows[0]["error"]


def test_setup_errors_are_raised_before_any_work(maps, tmp_path):
    with pytest.raises(CompileError, match=r"metric 'sft_rmse': chain 'tiny-os' has 0 dft"):
        run_sweep(_spec(maps, metrics=[{"name": "sft_rmse"}]), tmp_path / "o", scheduler="sync")
    with pytest.raises(CompileError, match=r"node 'nope' is not in chain"):
        run_sweep(_spec(maps, metrics=[{"name": "cfar", "node": "nope"}]), tmp_path / "o",
                  scheduler="sync")
    with pytest.raises(RadarConfigError, match=r"folder .* does not exist"):
        run_sweep(_spec(maps.parent / "gone"), tmp_path / "o", scheduler="sync")
    small = {**CHAIN, "nodes": [{**CHAIN["nodes"][0], "shape": {"range": 8, "doppler": 8}},
                                *CHAIN["nodes"][1:]]}
    with pytest.raises(IRError, match=r"input 'rd': array shape \(16, 8\)"):
        run_sweep(_spec(maps, chains={"os": small}), tmp_path / "o", scheduler="sync")
    assert not (tmp_path / "o" / RESULTS_FILE).exists()


def test_command_runs_and_prints_json(maps, tmp_path, capsys):
    spec_file = tmp_path / "s.yaml"
    data = _spec(maps).model_dump(mode="json")
    spec_file.write_text(yaml.safe_dump(data, sort_keys=False))
    parser = argparse.ArgumentParser(prog="radarsnn")
    add_parsers(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["sweep", str(spec_file), "--scheduler", "sync", "--out",
                              str(tmp_path / "cli"), "--json"])
    assert args.func(args) == 0
    printed = json.loads(capsys.readouterr().out)
    assert (printed["cells"], printed["run"], printed["failed"]) == (12, 12, 0)
    args = parser.parse_args(["sweep", str(spec_file), "--scheduler", "sync", "--out",
                              str(tmp_path / "cli"), "--quiet"])
    assert args.func(args) == 0
    text = capsys.readouterr().out
    assert "cfar.sensitivity" in text and "0 cells run, 12 skipped" in text


def test_no_progress_bar_when_stderr_is_not_a_terminal(maps, tmp_path, capsys):
    """Issue 19 item 8: a sweep logged to a file draws no tqdm bar (it did: ``\\r``-joined bars)."""
    run_sweep(_spec(maps), tmp_path / "out", scheduler="sync", quiet=False, max_cells=2)
    assert "\r" not in capsys.readouterr().err
