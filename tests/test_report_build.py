"""The whole report: pipeline quantize -> split -> place -> report, JSON schema, Markdown, PNG."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from compiler.hardware import load_profile
from compiler.hardware.reference_networks import dft_network, imaging_network, os_cfar_network
from compiler.passes.base import CompileContext, run_pipeline
from compiler.passes.place import Place
from compiler.passes.quantize import Quantize
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.program import CompiledProgram, Segment
from compiler.report import build_report, network_runs
from ir import Graph
from ir.errors import BudgetError
from radarsnn.cli import main

ROOT = Path(__file__).resolve().parents[1]
CARRADA = ROOT / "examples" / "chains" / "carrada_rd_oscfar.yaml"
def compiled(net, target: str, repetitions: str = "auto") -> CompiledProgram:
    prog = CompiledProgram(graph=Graph.from_yaml(CARRADA), segments=[
        Segment(kind="spiking", inputs=["rd"], outputs=["det"], network=net)])
    ctx = CompileContext(target=load_profile(target))
    passes = [Quantize(), Split(repetitions=repetitions), Place(repetitions=repetitions),
              ReportPass()]
    return run_pipeline(passes, ctx, prog)


def test_carrada_os_cfar_stand_in_on_loihi():
    net = os_cfar_network()
    prog = compiled(net, "loihi")
    data = json.loads(prog.records["report"].to_json())
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
    assert "ra_map" not in io  # the chain has no angle stage
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
    totals = rep.data["totals"]  # stored and instance synapse counts, each named
    assert (f"synapses stored {totals['synapses_stored']:,} (synapse instances "
            f"{totals['synapses']:,})").replace(",", " ") in md
    assert "| inputs | neurons | synapse_instances | synapses_stored |" in md
    assert "ra_map" not in md
    png = rep.save_core_map(tmp_path / "cores.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_without_networks_or_placement():
    rep = build_report(CompiledProgram(graph=Graph.from_yaml(CARRADA)), frame_rate_hz=20.0)
    assert rep.data["stages"] == [] and rep.data["cores"] == []
    assert rep.data["frame_io"][1]["bandwidth_Mbit_s"] == pytest.approx(5.24288)
    assert rep.data["latency"]["fits"] is None  # unbounded: no step duration


def test_imaging_chain_fails_with_what_to_change():
    net = imaging_network()
    for target in ("loihi", "loihi2", "spinnaker2"):
        # auto multiplexes rng, dop and ang; the OS-CFAR over 192 angles (a stencil: one
        # repetition) alone is 25 165 824 neurons
        with pytest.raises(BudgetError, match=r"at least [\d,]+ cores \([\d,]+ chips.*"
                           r"1 available.*node 'det' \(motif os_cfar.*25,165,824 neurons.*"
                           r"even with every repeated stage time-multiplexed") as e:
            compiled(net, target)
        assert e.value.node == "det"
        with pytest.raises(BudgetError, match=r"node 'rng'.*time-multiplex the 3 repeated"):
            compiled(net, target, "spatial")


def test_multiplexed_stage_in_the_report():
    prog = compiled(dft_network(), "loihi")
    data = json.loads(prog.records["report"].to_json())
    (stage,) = data["stages"]
    # one instance (1 024 neurons, 512 x 1 024 synapses x 24 bit) run 256 times of 200 steps
    assert stage["multiplexed"] is True and stage["repetitions"] == 256
    assert (stage["neurons"], stage["synapses"]) == (1024, 512 * 1024)
    assert stage["synapse_memory_bits"] == 512 * 1024 * 24
    assert stage["steps_per_frame"] == 256 * 200
    assert stage["cores"] == data["totals"]["cores"] == len(data["cores"])
    lat = data["latency"]
    assert lat["networks"][0]["runs"] == 256 and lat["total_steps"] == 51_200
    # 51 200 steps x 10 us = 0.512 s > 0.1 s; it would fit with steps of 0.1 / 51 200 s
    assert lat["total_s"] == pytest.approx(0.512) and lat["fits"] is False
    assert lat["max_step_s"] == pytest.approx(0.1 / 51_200)
    assert "assumption" in lat["step_note"]
    md = prog.records["report"].to_markdown()
    # 512 inputs (256 samples x Re, Im); 12 uniform blocks would hold 86 neurons x 512
    # synapses x 24 bit = 1 056 768 > 1 048 576 bit: 13 cores
    assert "| rng | dft | 512 | 1 024 | 524 288 | 200 | 256 | yes | 51 200 | 13 |" in md
    assert "time_step_s = 1e-05 s is an assumption of the loihi profile" in md


def test_network_runs_by_hand():
    assert network_runs([]) == 1
    assert network_runs([{"multiplexed": False, "repetitions": 4}]) == 1
    assert network_runs([{"multiplexed": True, "repetitions": 4},
                         {"multiplexed": True, "repetitions": 3}]) == 7


#: loihi's budgets and formats with neurons that have every feature (a hypothetical chip):
#: the stock Loihi 1 refuses the time-coded S-FT (no non-leaking current, fire-once, gates).
PROGRAMMABLE = {"current_decay_offset_lsb": 0, "full_voltage_decay": True,
                "reset": "programmable", "fire_once": "programmable",
                "threshold_schedule": True, "input_gate": True}


def test_carrada_chain_is_refused_on_the_stock_loihi(capsys):
    assert main(["report", str(CARRADA), "--target", "loihi", "--json"]) != 0
    err = json.loads(capsys.readouterr().out)
    assert err["type"] == "CompileError" and err["node"] == "rng__moving"
    assert "non-leaking current" in err["error"] and "motifs={'rng': 'host'}" in err["error"]


def test_carrada_chain_reports_on_loihi_budgets_from_the_cli(capsys, tmp_path):
    import yaml

    doc = {**load_profile("loihi").model_dump(), **PROGRAMMABLE}
    (tmp_path / "loihi_prog.yaml").write_text(yaml.safe_dump(doc))
    assert main(["report", str(CARRADA), "--target", str(tmp_path / "loihi_prog.yaml"),
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rows = {r["node"]: r for r in data["stages"]}
    # rng (256 repetitions) and dop (1 024) multiplexed; the OS-CFAR stays spatial (Table 3)
    assert [(n, r["repetitions"], r["multiplexed"]) for n, r in rows.items()] == [
        ("rng__moving", 256, True), ("dop__moving", 1024, True), ("det", 1, False)]
    # Table 3's 16 384 x 177 synapses, plus one split term per CUT whose clipped-edge rank
    # k_eff is odd and above 127 (an 8-bit mantissa with one exponent cannot hold it): 768
    assert (rows["det"]["neurons"], rows["det"]["synapses"]) == (16_384, 2_899_968 + 768)
    assert data["totals"]["cores"] <= 128
    lat = data["latency"]
    # (256 + 1 024) runs of 768 steps + 100 steps of the CFAR network
    assert lat["total_steps"] == 1280 * 768 + 100 and lat["fits"] is False


def test_carrada_compiles_for_loihi_budgets():
    from compiler.calibration import synthetic_inputs
    from compiler.compile import compile_graph

    g = Graph.from_yaml(CARRADA)
    target = load_profile("loihi").model_copy(update=PROGRAMMABLE)
    prog = compile_graph(g, target=target, calibration_inputs=synthetic_inputs(g, seed=0))
    assert set(prog.records["timings"]) >= {"lower", "split", "place", "report"}
    assert prog.records["report"].data["totals"]["cores"] <= 128
    # issue 6 acceptance, computed from the compiled chain's JSON report
    data = json.loads(prog.records["report"].to_json())
    det = next(s for s in data["stages"] if s["node"] == "det")
    assert (det["motif"], det["inputs"], det["neurons"], det["synapses"], det["repetitions"]) == (
        "time", 16_384, 16_384, 2_899_968 + 768, 1)  # + the split edge CUT terms (above)
    io = {r["name"]: r for r in data["frame_io"]}
    assert round(io["raw_cube"]["memory_kB"]) == 262
    assert round(io["rd_map"]["memory_kB"], 1) == 32.8
    assert round(io["rd_map"]["bandwidth_Mbit_s"], 2) == 2.62
    assert "ra_map" not in io  # no angle stage: no RA map row
    asked = build_report(prog, n_angle_bins=256)  # CARRADA's RA map, computed elsewhere
    io = {r["name"]: r for r in asked.data["frame_io"]}
    assert round(io["ra_map"]["memory_kB"]) == 131
    assert round(io["ra_map"]["bandwidth_Mbit_s"], 1) == 10.5


def test_a_chain_without_a_radar_cube_or_map_says_so_instead_of_an_empty_table():
    """A plain ``input`` chain has no frame-I/O rows; the Markdown said ``|  |`` / ``|``."""
    import numpy as np

    from compiler.compile import compile_graph

    chain = Graph.from_yaml("""name: plain
nodes:
  - {id: x, op: input, shape: {sample: 16}}
  - {id: rng, op: dft, input: x, axis: sample, out_axis: range, keep: positive}
  - {id: out, op: output, input: rng}
""")
    frames = np.random.default_rng(0).standard_normal((2, 16))
    report = compile_graph(chain, "loihi2", calibration_inputs={"x": frames},
                           accuracy="off").records.report
    assert report.data["frame_io"] == []
    text = report.to_markdown()
    section = text.split("## Frame I/O at 10 frames/s\n\n")[1].split("\n\n")[0]
    assert section.startswith("None: the chain has no `adc_input` cube")
    assert all(line.strip() not in ("|  |", "|") for line in text.splitlines())
