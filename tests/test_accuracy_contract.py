"""The accuracy contract measured at compile time, and ``motifs="auto"`` climbing the ladders."""

from __future__ import annotations

import json

import numpy as np
import pytest

from backends.reference import ReferenceSimulator
from compiler.accuracy.contract import Contract, StageCheck, Tolerances
from compiler.accuracy.select import LADDERS, search
from compiler.compile import compile_graph
from ir import Graph
from ir.errors import AccuracyError, BudgetError


def _frames(n: int, seed: int) -> np.ndarray:
    """Noise of unit rms plus one moving tone ~70 dB above it, a new position per frame."""
    rng = np.random.default_rng(seed)
    t, m = np.arange(64), np.arange(8)[:, None]
    out = []
    for _ in range(n):
        x = rng.normal(size=(8, 64)) + 1j * rng.normal(size=(8, 64))
        x += 3e3 * np.exp(2j * np.pi * ((5 + rng.uniform(0, 20)) * t[None] / 64
                                        + rng.uniform(1, 3) * m / 8))
        out.append(x)
    return np.stack(out)


RD = Graph.from_dict({"name": "rd", "nodes": [
    {"id": "x", "op": "input", "shape": {"chirp": 8, "sample": 64}, "complex": True},
    {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
    {"id": "d", "op": "dft", "input": "f", "axis": "chirp", "out_axis": "doppler"},
    {"id": "o", "op": "output", "input": "d"}]})


#: The resonator's linear time read-out with per-bin scales from the calibration frames:
#: a new frame's tone in a bin that held noise there is clipped (mechanism of the log code).
CLIPPING = {"resonator_readout": "time"}


def test_a_stage_that_loses_signal_cells_is_refused_and_named():
    with pytest.raises(AccuracyError, match=r"stage 'f' .*lost") as err:
        compile_graph(RD, "spinnaker2", motifs={"dft": "resonator"}, options=CLIPPING,
                      calibration_inputs={"x": _frames(3, 0)}, simulator=ReferenceSimulator())
    assert err.value.node == "f"
    assert "accuracy='warn'" in str(err.value)


def test_warn_keeps_the_best_and_records_what_fails():
    p = compile_graph(RD, "spinnaker2", motifs={"dft": "resonator"}, options=CLIPPING,
                      calibration_inputs={"x": _frames(3, 0)}, simulator=ReferenceSimulator(),
                      accuracy="warn")
    contract = p.records.accuracy
    assert not contract.holds and contract.held_out and contract.n_frames == 1
    assert [s.node for s, _ in contract.failing()][0] == "f__moving"
    assert any("FAILS" in line for line in contract.lines())


@pytest.mark.parametrize("target", ["loihi2", "spinnaker2"])
def test_auto_keeps_a_spiking_chain_that_holds_on_held_out_frames(target):
    rate = {"frame_rate_hz": 1.0} if target == "spinnaker2" else None  # its 1 ms steps
    p = compile_graph(RD, target, calibration_inputs={"x": _frames(3, 0)}, options=rate,
                      simulator=ReferenceSimulator())
    sel = p.records.extra["motif_selection"]
    assert p.records.accuracy.holds and sel["host_ops"] == []
    assert p.records.motifs["d__moving"] != "host"
    for s in p.records.accuracy.stages:  # far below the noise floor, nothing lost
        assert s.figures["error_db"] < -10 and s.figures["lost"] == 0


def _ca_on_linear_power(n_frames: int):
    """Noise maps in linear power with three returns 20-60 dB up per frame, and a CA-CFAR."""
    rng = np.random.default_rng(3)
    maps = rng.exponential(size=(n_frames, 16, 64)) * 1e6
    for f in range(n_frames):
        for _ in range(3):
            maps[f, rng.integers(16), rng.integers(64)] *= 10 ** rng.uniform(2, 6)
    g = Graph.from_dict({"name": "ca", "nodes": [
        {"id": "p", "op": "input", "shape": {"doppler": 16, "range": 64}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "p", "kind": "ca", "guard": [1, 1],
         "train": [2, 4], "pfa": 1e-3, "edge": ["wrap", "clip"]},
        {"id": "o", "op": "output", "input": "det"}]})
    return maps, g


def test_ca_cfar_on_linear_power_is_measured_spiking_before_any_host_fallback():
    maps, g = _ca_on_linear_power(4)
    p = compile_graph(g, "loihi2", calibration_inputs={"p": maps},
                      simulator=ReferenceSimulator())
    attempts = p.records.extra["motif_selection"]["attempts"]
    assert attempts[0]["config"] == {"cfar": "time"} and attempts[0]["holds"] is not None
    assert p.records.accuracy.holds
    if p.records.motifs["det"] == "host":  # the fallback comes only after spiking rungs
        assert [a["config"]["cfar"] for a in attempts] == [c.label for c in LADDERS["cfar"]]


class _Fake:
    """A program stand-in: the rungs it was built with, a report with its steps."""

    def __init__(self, motifs, steps):
        self.motifs, self.steps = motifs, steps
        self.records = type("R", (), {"report": type("Rep", (), {
            "data": {"latency": {"total_steps": steps, "fits": steps <= 100,
                                 "frame_period_s": 1e-3, "total_s": steps * 1e-5,
                                 "networks": [{"network": "n", "runs": 2,
                                               "time_steps": steps // 2,
                                               "latency_steps": steps}]}}})()})()
        self.graph = type("G", (), {"op": staticmethod(
            lambda n: type("O", (), {"op": n})())})()


def _contract(failing_nodes):
    tol = Tolerances()
    stages = [StageCheck(node=n, motif="m", kind="values",
                         figures={"error_db": 0.0 if n in failing_nodes else -30.0,
                                  "lost": 0.0, "signal_cells": 1}) for n in ("dft", "cfar")]
    return Contract(stages=stages, tolerances=tol, n_frames=1)


def test_the_search_climbs_the_failing_op_and_tries_the_host_last():
    def build(motifs, options):
        return _Fake(motifs, 10)

    def measure(p):  # the CFAR holds only on the host; the DFT holds once resonator
        bad = [] if p.motifs["dft"] != "time" else ["dft"]
        bad += [] if p.motifs["cfar"] == "host" else ["cfar"]
        return _contract(bad)

    _, sel = search(["dft", "cfar"], build, measure)
    configs = [a.config for a in sel.attempts]
    assert configs[0] == {"dft": "time", "cfar": "time"}
    assert configs[1]["dft"] == LADDERS["dft"][1].label  # the first failing stage climbs first
    assert configs[-1]["cfar"] == "host" and sel.host_ops == ["cfar"]
    assert all(c["cfar"] != "host" for c in configs[:-1])  # spiking rungs all tried before


def test_the_deadline_never_moves_a_stage_to_the_host():
    def build(motifs, options):
        return _Fake(motifs, 1000)  # never fits

    tried = []

    def build_and_log(motifs, options):
        tried.append(dict(motifs))
        return build(motifs, options)

    with pytest.raises(BudgetError, match=r"frame deadline.*0\.01 s per frame.*'n' alone runs 2"):
        search(["dft", "cfar"], build_and_log, lambda p: _contract([]))
    # only a change of motif can cut steps: time -> resonator, no option rungs, no host
    assert tried == [{"dft": "time", "cfar": "time"}, {"dft": "resonator", "cfar": "time"}]


def test_a_chip_too_small_never_moves_a_stage_to_the_host():
    tried = []

    def build(motifs, options):  # a spiking CFAR never fits this chip; the host one would
        tried.append(dict(motifs))
        if motifs["cfar"] != "host":
            raise BudgetError("node 'cfar' needs 65,536 neurons, 38,912 available")
        return _Fake(motifs, 10)

    with pytest.raises(BudgetError, match="65,536 neurons"):
        search(["dft", "cfar"], build, lambda p: _contract([]))
    assert tried and all(m["cfar"] != "host" for m in tried)


def test_the_cli_measures_with_calibration_frames_and_refuses_a_loss(tmp_path, capsys):
    from radarsnn.cli import main

    chain, frames = tmp_path / "rd.yaml", tmp_path / "x.npy"
    chain.write_text(RD.to_yaml())
    np.save(frames, _frames(3, 0))
    ok = ["compile", str(chain), "-c", str(frames), "-o", str(tmp_path / "a"), "--quiet"]
    assert main([*ok[:-1]]) == 0
    out = capsys.readouterr().out
    assert "accuracy on 1 held-out frame(s)" in out and "FAILS" not in out
    assert "## Accuracy on 1 held-out frame(s): holds" in (tmp_path / "a/report.md").read_text()
    lossy = [*ok[:4], "-t", "spinnaker2", "-m", "dft=resonator", "--option",
             "resonator_readout=time", "-o", str(tmp_path / "b"), "--quiet"]
    assert main(lossy) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "stage 'f'" in err[0] and "lost" in err[0]
    assert not (tmp_path / "b").exists()
    assert main([*lossy, "--accuracy", "warn"]) == 0
    assert "warning: stage 'f__moving'" in capsys.readouterr().err


def test_one_check_frame_with_a_frames_axis_is_scored_on_the_detector_axes():
    # a single held-out frame keeps its frames axis (split_folds): the CFAR's window axes
    # are then one further along, and a map is still one frame's [doppler, range] map
    from compiler.accuracy.check import check_program
    from compiler.accuracy.simulator import SimulatedFrames
    from ir import evaluate

    class Exact:
        name = "exact"

        def run(self, program, inputs):
            return SimulatedFrames(values=evaluate(program.graph, inputs))

    rng = np.random.default_rng(5)
    power = rng.exponential(size=(16, 64))
    power[4, 10] = power[9, 40] = 1e4
    g = Graph.from_dict({"name": "ca", "nodes": [
        {"id": "p", "op": "input", "shape": {"doppler": 16, "range": 64}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "p", "kind": "ca", "guard": [1, 1],
         "train": [2, 4], "pfa": 1e-3, "edge": ["wrap", "clip"]},
        {"id": "o", "op": "output", "input": "det"}]})
    program = compile_graph(g, None, motifs={"det": "time"}, calibration_inputs={"p": power})
    one = check_program(program, {"p": power}, Exact()).stages[0].figures
    framed = check_program(program, {"p": power[None]}, Exact()).stages[0].figures
    assert one["maps"] == framed["maps"] == 1
    assert framed["objects"] == one["objects"] >= 2


def test_a_deadline_refusal_names_the_stage_of_the_slowest_network():
    # spinnaker2's 1 ms steps: the resonator DFTs keep the contract but not 20 frames/s
    with pytest.raises(BudgetError, match=r"frame deadline: .* 0\.074 s per frame against a "
                                          r"frame period of 0\.05 s; network 'rd' \(stage 'f'\) "
                                          r"alone runs 1 .* x 65 steps"):
        compile_graph(RD, "spinnaker2", calibration_inputs={"x": _frames(3, 0)},
                      simulator=ReferenceSimulator(), options={"frame_rate_hz": 20})


def test_the_cli_summary_says_which_stage_the_search_kept_on_the_host(tmp_path, capsys):
    from radarsnn.cli import main

    maps, g = _ca_on_linear_power(3)
    chain, frames = tmp_path / "ca.yaml", tmp_path / "p.npy"
    chain.write_text(g.to_yaml())
    np.save(frames, maps)
    argv = ["compile", str(chain), "-c", str(frames), "-o", str(tmp_path / "a")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert ("on the host: cfar (no spiking configuration kept the contract: time, "
            "time(cfar_steps=300), time(cfar_steps=1000))") in out
    assert main([*argv[:-1], str(tmp_path / "b"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["host_ops"] == ["cfar"]
