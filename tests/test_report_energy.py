"""Energy and latency per frame: tiny networks by hand, cited constants, the DSP beside it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from compiler.hardware import BUILTIN_PROFILES, load_profile
from compiler.hardware.reference_networks import os_cfar_network
from compiler.passes.base import CompileContext, run_pipeline
from compiler.passes.place import Place
from compiler.passes.quantize import Quantize
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.program import CompiledProgram, Segment
from compiler.report.conventional import DSP, conventional_rows, fft_cycles
from compiler.snn import Encoder, LatencyCode, NeuronParams, Population, SpikingNetwork
from compiler.snn.matrix_projection import MatrixProjection
from ir import Graph
from ir.errors import CompileError

ROOT = Path(__file__).resolve().parents[1]
CARRADA = ROOT / "examples" / "chains" / "carrada_rd_oscfar.yaml"
# Davies et al. 2018, Table 2 (loihi.yaml): synaptic op, active neuron update, spike in a tile
E_SYN, E_NEU, E_SPK, P_STATIC = 23.6e-12, 81e-12, 1.7e-12, 0.104


def tiny() -> SpikingNetwork:
    """2 latency-coded inputs -> 3 fire-once neurons, dense 2 x 3, 10 steps (node 'f')."""
    origin = {"node": "f", "motif": "dft"}
    return SpikingNetwork(
        name="tiny", n_steps=10,
        populations=[Population(id="x", shape={"i": 2}, source=True, origin=origin),
                     Population(id="y", shape={"o": 3}, origin=origin,
                                params=NeuronParams(reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 3)), origin=origin)],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))]).validate()


def report(net: SpikingNetwork, target: str):
    g = Graph.from_dict({"name": "t", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 2}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
        {"id": "o", "op": "output", "input": "f"}]})
    prog = CompiledProgram(graph=g, segments=[
        Segment(kind="spiking", inputs=["x"], outputs=["f"], network=net)])
    passes = [Quantize(), Split(), Place(), ReportPass()]
    return run_pipeline(passes, CompileContext(target=load_profile(target)), prog).records.report


def test_tiny_network_by_hand_on_loihi():
    rep = report(tiny(), "loihi")
    e = rep.data["energy"]
    (s,) = e["stages"]
    # bounds: each input spikes once over 3 synapses, 3 neurons x 10 steps, each fires once
    assert (s["synaptic_events"], s["neuron_updates"], s["spikes"]) == (6, 30, 3)
    assert s["basis"] == "bound"
    dynamic = 6 * E_SYN + 30 * E_NEU + 3 * E_SPK  # 141.6 + 2430 + 5.1 = 2576.7 pJ
    assert s["energy_J"] == pytest.approx(2576.7e-12) and e["dynamic_J"] == pytest.approx(dynamic)
    assert s["latency_s"] == pytest.approx(10 * 1e-5)
    assert e["static_J"] == pytest.approx(P_STATIC * 1 * 10 * 1e-5)
    assert e["total_J"] == pytest.approx(dynamic + P_STATIC * 1e-4)
    # the DSP: one 2-point DFT padded to a 16-point DSP_fft16x16, 77 cycles at 600 MHz
    assert s["dsp_cycles"] == 77 and e["dsp_J"] == pytest.approx(77 * 1.4231e-9)
    assert e["dsp_latency_s"] == pytest.approx(77 / 600e6)
    assert e["total_to_dsp"] == pytest.approx(e["total_J"] / e["dsp_J"])
    md = rep.to_markdown()
    assert "## Energy and latency per frame" in md
    assert "Davies et al., IEEE Micro 38(1) 2018, Table 2" in md and "SPRUEB8" in md
    # 0.104 W x 100 us = 10.4 uJ of leakage against 2.577 nJ of operations
    assert rep.energy_line().startswith("energy ≈ 10.4 µJ/frame on loihi (dynamic 2.577 nJ "
                                        "+ static 10.4 µJ; bound counts); conventional DSP")


def test_null_constants_render_as_not_published():
    rep = report(tiny(), "loihi2")
    e = rep.data["energy"]
    assert e["stages"][0]["energy_J"] is None and e["dynamic_J"] is None
    assert e["total_J"] is None and e["total_to_dsp"] is None
    assert e["dsp_J"] == pytest.approx(77 * 1.4231e-9)  # the DSP figure stays
    md = rep.to_markdown()
    row = next(ln for ln in md.splitlines() if ln.startswith("| f | bound"))
    assert "not published" in row and "0" not in row.split("|")[6]
    assert "energy per frame on loihi2: not published" in rep.energy_line()
    none = report(tiny(), "unbounded").data["energy"]
    assert none["dynamic_J"] is None and "gives no energy constants" in none["note"]


def test_dsp_cycles_by_hand():
    assert [fft_cycles(n) for n in (16, 64, 192, 256, 1024)] == [
        (12 + 19) * 1 + 16 + 30, (48 + 19) * 2 + 64 + 30, 919, 919, (768 + 19) * 4 + 1024 + 30]
    g = Graph.from_yaml(CARRADA)
    rows = {r["node"]: r for r in conventional_rows(g, ["rng", "dop", "mag", "rd", "det"])}
    assert rows["rng"]["cycles"] == 4 * 64 * 919  # 256 FFTs of 256 points (window separate)
    assert rows["dop"]["cycles"] == 4 * 256 * 228
    assert rows["mag"]["cycles"] == rows["rd"]["cycles"] == 4 * 64 * 256
    assert rows["det"]["cycles"] == 64 * 256 * 177  # Table 1: N + 1 compares per cell
    assert rows["det"]["energy_J"] == pytest.approx(64 * 256 * 177 * 1.4231e-9)


def test_measured_counts_replace_the_bounds():
    from radarsnn import compile_graph

    # an OS-CFAR: a motif loihi's stock neurons run (its DFT motifs are refused there)
    g = Graph.from_dict({"name": "r", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 64}, "domain": "power"},
        {"id": "f", "op": "cfar", "input": "x", "kind": "os", "axes": ["range"], "guard": [1],
         "train": [4], "alpha": 4.0, "k": 6},
        {"id": "o", "op": "output", "input": "f"}]})
    x = np.random.default_rng(0).exponential(size=(6, 64))
    x[:, 20] += 40.0
    rep = compile_graph(g, "loihi", calibration_inputs={"x": x}, accuracy="warn").records.report
    (row,) = rep.data["stages"]
    (s,) = rep.data["energy"]["stages"]
    assert s["basis"] == "measured" and rep.data["energy"]["basis"] == "measured"
    assert s["spikes"] == row["spikes_measured"] < row["spikes_bound"]
    assert s["synaptic_events"] == row["synaptic_events_measured"]
    assert s["energy_J"] == pytest.approx(s["synaptic_events"] * E_SYN
                                          + s["neuron_updates"] * E_NEU + s["spikes"] * E_SPK)
    assert "measured on the checked frames" in rep.data["energy"]["note"]


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_every_energy_figure_cites_its_source(name):
    energy = load_profile(name).energy
    if energy is None:
        assert name == "unbounded"
        return
    for key, fig in energy:
        assert fig is not None, f"{name}.{key} is left out: give it, null with 'not published'"
        src = fig.source
        if fig.value is None:
            assert src.startswith("not published"), (name, key)
            continue
        assert re.search(r"(19|20)\d\d", src) or "assumption" in src, (name, key)
        m = re.search(r"([\d.]+) (pJ|W)\b", src)  # the number the value was written from
        if m and not src.startswith("derived"):
            scale = 1e-12 if m.group(2) == "pJ" else 1.0
            assert fig.value == pytest.approx(float(m.group(1)) * scale), (name, key)
    for key, fig in DSP.items():
        assert re.search(r"(19|20)\d\d", fig.source) or "assumption" in fig.source, key


def test_os_cfar_stand_in_json_roundtrip_is_plain():
    net = os_cfar_network(16, 32)
    prog = CompiledProgram(graph=Graph.from_yaml(CARRADA), segments=[
        Segment(kind="spiking", inputs=["rd"], outputs=["det"], network=net)])
    passes = [Quantize(), Split(), Place(), ReportPass()]
    rep = run_pipeline(passes, CompileContext(target=load_profile("loihi")), prog).records.report
    e = json.loads(rep.to_json())["energy"]
    (s,) = e["stages"]
    # 512 fire-once cells, each seeing <= 177 latency-coded inputs once, 100 steps
    assert s["neuron_updates"] == 512 * 100 and s["spikes"] == 512
    assert s["dsp_cycles"] == 64 * 256 * 177  # the chain's det node: the 64 x 256 map
    assert {c["name"] for c in e["constants"]} >= {"loihi.synaptic_op_j", "dsp.clock_hz"}


def test_a_user_profile_gives_its_own_energy_figures(tmp_path):
    f = tmp_path / "chip.yaml"
    f.write_text("name: chip\nunbounded: true\ntime_step_s: 1.0e-6\nenergy:\n"
                 "  synaptic_op_j: {value: 1.0e-12, source: 'assumption: a guess'}\n")
    p = load_profile(f)
    assert p.energy.synaptic_op_j.value == 1e-12 and p.energy.neuron_update_j is None
    f.write_text("name: chip\nunbounded: true\nenergy:\n  per_op_j: {value: 1, source: x}\n")
    with pytest.raises(CompileError, match="energy.per_op_j"):
        load_profile(f)
    f.write_text("name: chip\nunbounded: true\nenergy:\n  spike_j: {value: -1, source: x}\n")
    with pytest.raises(CompileError, match="energy.spike_j.value"):
        load_profile(f)
