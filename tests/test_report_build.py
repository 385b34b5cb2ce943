"""The whole report: pipeline quantize -> split -> place -> report, JSON schema, Markdown, PNG."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from compiler.hardware import load_profile
from compiler.hardware.reference_networks import imaging_network, os_cfar_network
from compiler.passes.base import CompileContext, run_pipeline
from compiler.passes.place import Place
from compiler.passes.quantize import Quantize
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.program import CompiledProgram, Segment
from compiler.report import build_report
from ir import Graph
from ir.errors import BudgetError

ROOT = Path(__file__).resolve().parents[1]
CARRADA = ROOT / "examples" / "chains" / "carrada_rd_oscfar.yaml"
PASSES = [Quantize(), Split(), Place(), ReportPass()]


def compiled(net, target: str) -> CompiledProgram:
    prog = CompiledProgram(graph=Graph.from_yaml(CARRADA), segments=[
        Segment(kind="spiking", inputs=["rd"], outputs=["det"], network=net)])
    return run_pipeline(PASSES, CompileContext(target=load_profile(target)), prog)


def test_carrada_os_cfar_stand_in_on_loihi_under_a_second():
    net = os_cfar_network()
    t0 = time.perf_counter()
    prog = compiled(net, "loihi")
    elapsed = time.perf_counter() - t0
    data = json.loads(prog.records["report"].to_json())
    assert elapsed < 1.0
    assert data["schema"] == "radarsnn-report/1" and data["target"] == "loihi"
    (stage,) = data["stages"]
    for key in ("node", "motif", "inputs", "neurons", "synapses", "time_steps", "repetitions",
                "cores"):
        assert key in stage
    assert (stage["inputs"], stage["neurons"], stage["synapses"], stage["repetitions"],
            stage["cores"]) == (16_384, 16_384, 2_899_968, 1, 67)
    # loihi stores every synapse inside the map: 2 851 584 x 24 bit
    assert stage["synapse_memory_bits"] == 2_851_584 * 24
    io = {r["name"]: r for r in data["frame_io"]}
    assert round(io["raw_cube"]["memory_kB"]) == 262 and round(io["rd_map"]["memory_kB"], 1) == 32.8
    assert round(io["ra_map"]["bandwidth_Mbit_s"], 1) == 10.5
    assert [r["total"] for r in data["cfar_ops"]] == [177, 276]
    assert data["latency"]["total_s"] == pytest.approx(100 * 1e-5) and data["latency"]["fits"]
    assert data["totals"]["neurons"] == 16_384 and data["totals"]["cores"] == 67
    assert len(data["cores"]) == 67
    assert all(max(c["utilisation"]) <= 1.0 for c in data["cores"])
    assert data["traffic"]["basis"] == "bound" and data["traffic"]["inter_core"] == 0


def test_markdown_and_core_map(tmp_path):
    rep = compiled(os_cfar_network(16, 32), "spinnaker2").records["report"]
    md = rep.to_markdown()
    assert md.startswith("# Resource report: carrada-rd-oscfar on spinnaker2")
    assert "| node | motif | inputs | neurons | synapses |" in md and "| det | os_cfar |" in md
    assert "OS-CFAR (spiking) | 176 | 100 | 276" in md
    png = rep.save_core_map(tmp_path / "cores.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_without_networks_or_placement():
    rep = build_report(CompiledProgram(graph=Graph.from_yaml(CARRADA)), frame_rate_hz=20.0)
    assert rep.data["stages"] == [] and rep.data["cores"] == []
    assert rep.data["frame_io"][1]["bandwidth_Mbit_s"] == pytest.approx(5.24288)
    assert rep.data["latency"]["fits"] is None  # unbounded: no step duration


def test_imaging_chain_fails_fast_with_what_to_change():
    net = imaging_network()
    t0 = time.perf_counter()
    for target in ("loihi", "loihi2", "spinnaker2"):
        with pytest.raises(BudgetError, match=r"at least [\d,]+ cores \([\d,]+ chips.*"
                           r"1 available.*node 'rng'"):
            compiled(net, target)
    assert time.perf_counter() - t0 < 30
