"""Segment boundaries in the report (compiler.report.boundaries) and the whole tracking chain
compiled, partitioned into spiking and host segments, and run."""

from __future__ import annotations

import json

import numpy as np
import pytest

from backends.reference.program import run_program
from compiler.chains_host import tracking_chain
from compiler.compile import compile_graph
from compiler.lowering import default_registry
from compiler.program import CompiledProgram, Segment
from compiler.report import build_report
from compiler.report.boundaries import boundary_rows, segment_names
from ir import Graph
from ir.errors import CompileError
from ir.ops import Cluster, Track
from radar.clustering import cluster_detections
from radar.config import RadarConfig
from radar.scene import Scene, Target, simulate_frame
from radar.tracking import track_sequence


def _hand_program() -> CompiledProgram:
    g = Graph.from_dict({"name": "h", "nodes": [
        {"id": "x", "op": "input", "shape": {"frame": 2, "range": 8}, "domain": "power"},
        {"id": "m", "op": "log", "input": "x"},
        {"id": "t1", "op": "threshold", "input": "m", "value": 0.0},
        {"id": "t2", "op": "threshold", "input": "m", "value": 1.0},
        {"id": "o1", "op": "output", "input": "t1"},
        {"id": "o2", "op": "output", "input": "t2"}]})
    return CompiledProgram(graph=g, segments=[
        Segment("spiking", inputs=["x"], outputs=["m"]),
        Segment("host", inputs=["m"], outputs=["t1"], node="t1"),
        Segment("spiking", inputs=["m"], outputs=["t2"]),
        Segment("host", inputs=["t1"], outputs=["o1"], node="o1"),
        Segment("host", inputs=["t2"], outputs=["o2"], node="o2")])


def test_hand_worked_boundary_rows() -> None:
    p = _hand_program()
    assert segment_names(p) == ["spiking#0", "host:t1", "spiking#2", "host:o1", "host:o2"]
    rows = boundary_rows(p, frame_rate_hz=10.0, real_bits=16)
    got = [(r["kind"], r["from"], r["to"], r["node"], r["values_per_frame"],
            r["bits_per_value"], r["crossings"], r["bits_per_frame"], r["kB_per_frame"],
            r["Mbit_s"]) for r in rows]
    # 16 values per run over frame axis 2 -> 8 per frame.  x: 8 * 16 = 128 bit = 0.016 kB,
    # x 10 /s = 1 280 bit/s.  m read by host t1 (out once) and by spiking#2 (out and back in:
    # 2 * 128 = 256 bit).  t2 is a mask: 8 * 1 bit.  t1 -> o1 stays on the host.
    assert got == [
        ("host→spiking", "input", "spiking#0", "x", 8, 16, 1, 128, 0.016, 0.00128),
        ("spiking→host", "spiking#0", "host:t1", "m", 8, 16, 1, 128, 0.016, 0.00128),
        ("spiking→spiking via host", "spiking#0", "spiking#2", "m", 8, 16, 2, 256, 0.032,
         0.00256),
        ("spiking→host", "spiking#2", "host:o2", "t2", 8, 1, 1, 8, 0.001, 0.00008),
    ]


def test_complex_values_take_twice_the_bits_and_host_readers_share_one_row() -> None:
    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "a", "op": "input", "shape": {"sample": 4}, "complex": True},
        {"id": "f", "op": "dft", "input": "a", "axis": "sample"},
        {"id": "m", "op": "magnitude", "input": "f"},
        {"id": "o", "op": "output", "input": "f"}]})
    p = CompiledProgram(graph=g, segments=[
        Segment("spiking", inputs=["a"], outputs=["f"]),
        Segment("host", inputs=["f"], outputs=["m"], node="m"),
        Segment("host", inputs=["f"], outputs=["o"], node="o")])
    rows = boundary_rows(p, frame_rate_hz=20.0, real_bits=12)
    assert [(r["kind"], r["to"], r["bits_per_value"], r["bits_per_frame"]) for r in rows] == [
        ("host→spiking", "spiking#0", 24, 96), ("spiking→host", "host:m, host:o", 24, 96)]
    assert rows[1]["Mbit_s"] == pytest.approx(96 * 20 / 1e6)


def test_cluster_and_track_have_no_spiking_motif() -> None:
    reg = default_registry()
    assert reg.motifs(Cluster) == ["host"] and reg.motifs(Track) == ["host"]


# ------------------------------------------------------------------ the whole chain


def _tiny() -> tuple[Graph, np.ndarray]:
    cfg = RadarConfig(name="tiny", carrier_hz=77e9, slope_hz_per_s=29.3e12, fs_hz=10e6,
                      n_samples=32, n_chirps=16, chirp_period_s=36e-6, idle_s=6e-6,
                      adc_start_s=4e-6)
    scene = Scene(targets=(Target(range_m=12.0, velocity_mps=3.0),
                           Target(range_m=30.0, velocity_mps=-5.0)), noise_dbfs=-70.0)
    cubes = np.stack([simulate_frame(cfg, scene, seed=k).adc for k in range(2)])
    cfar = {"kind": "os", "axes": ["range", "doppler"], "guard": [1, 1], "train": [2, 2],
            "k": 15, "alpha": 4.0, "edge": ["clip", "wrap"]}
    return tracking_chain(cfg, n_frames=2, cfar=cfar, cluster={"max_clusters": 4}), cubes


def test_tracking_chain_compiles_into_spiking_and_host_segments_and_runs() -> None:
    graph, cubes = _tiny()
    program = compile_graph(graph, "loihi2", calibration_inputs={"adc": cubes})
    kinds = {s.node: s.kind for s in program.segments if s.kind == "host"}
    assert {"clu", "trk", "out"} <= set(kinds)
    assert [s.kind for s in program.segments].count("spiking") >= 1
    result = run_program(program, {"adc": cubes})
    v = result.values
    assert result.outputs["out"].shape == (2, 16, 7)
    # the host stages compute the reference on what the spiking segments decoded
    rd = v["rd"].transpose(0, 2, 1)                       # [frame, range, doppler]
    table = cluster_detections(v["det"].transpose(0, 2, 1) != 0, rd, max_clusters=4)
    np.testing.assert_array_equal(v["clu"], table)
    op = program.graph.op("trk")
    np.testing.assert_array_equal(v["trk"], track_sequence(table, **op.tracker_params()))
    assert v["clu"][:, 0, 0].tolist() == [1.0, 1.0]       # the targets were detected
    # every spiking<->host crossing is in the report, per radar frame
    rows = boundary_rows(program, frame_rate_hz=10.0, real_bits=16)
    det = next(r for r in rows if r["node"] == "det")
    assert (det["kind"], det["to"], det["bits_per_value"], det["values_per_frame"]) == (
        "spiking→host", "host:clu", 1, 16 * 32)
    assert rows[0]["node"] == "adc__moving" and rows[0]["bits_per_value"] == 32
    assert all(r["from"] != r["to"] for r in rows)
    report = build_report(program)
    assert report.data["boundaries"] == rows
    assert "## Segment boundaries" in report.to_markdown()
    assert json.loads(report.to_json())["boundaries"][0]["node"] == "adc__moving"


def test_a_spiking_motif_for_a_host_only_op_is_refused_naming_the_node() -> None:
    graph, cubes = _tiny()
    with pytest.raises(CompileError, match="node 'clu' \\(cluster\\): no motif 'dbscan'"):
        compile_graph(graph, motifs={"clu": "dbscan"}, calibration_inputs={"adc": cubes})
