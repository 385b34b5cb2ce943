"""Report tables: frame I/O (Table 3 top), CFAR op counts (Table 1), stage rows (Table 3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.reference import simulate
from compiler.hardware.reference_networks import os_cfar_network
from compiler.report.frame_io import frame_io, io_figures
from compiler.report.opcounts import cfar_op_counts, graph_cfar_op_counts
from compiler.report.stages import stage_rows
from compiler.snn import Encoder, LatencyCode, MatrixProjection, Population, SpikingNetwork
from ir import Graph

ROOT = Path(__file__).resolve().parents[1]
CARRADA = ROOT / "examples" / "chains" / "carrada_rd_oscfar.yaml"


def test_carrada_frame_io_is_computed():
    rows = {r["name"]: r for r in frame_io(Graph.from_yaml(CARRADA), frame_rate_hz=10.0,
                                           n_angle_bins=256)}
    raw, rd, ra = rows["raw_cube"], rows["rd_map"], rows["ra_map"]
    # 4 x 64 x 256 complex at 2 x 16 bit = 262 144 bytes; x 8 x 10 / 1e6 = 20.97 Mbit/s
    assert (raw["values"], raw["bits_per_value"], raw["bytes"]) == (65_536, 32, 262_144)
    assert raw["memory_kB"] == pytest.approx(262.144)
    assert raw["bandwidth_Mbit_s"] == pytest.approx(20.97152)
    # 64 x 256 x 16 bit = 32 768 bytes = 32.8 kB; 2.62 Mbit/s
    assert rd["source"] == "node 'rd'" and rd["memory_kB"] == pytest.approx(32.768)
    assert rd["bandwidth_Mbit_s"] == pytest.approx(2.62144)
    # 256 x 256 x 16 bit = 131 kB, 10.5 Mbit/s (angle bins from the option)
    assert ra["memory_kB"] == pytest.approx(131.072)
    assert ra["bandwidth_Mbit_s"] == pytest.approx(10.48576)
    # the paper's 197 kB is 24-bit samples: 65 536 x 24 / 8
    assert io_figures("raw", {"n": 65_536}, 24, 10.0, "")["memory_kB"] == pytest.approx(196.608)


def test_frame_io_options_and_missing_ra():
    g = Graph.from_yaml(CARRADA)
    rows = {r["name"]: r for r in frame_io(g, frame_rate_hz=20.0, real_bits=12)}
    assert "ra_map" not in rows
    assert rows["raw_cube"]["bits_per_value"] == 24
    assert rows["rd_map"]["bandwidth_Mbit_s"] == pytest.approx(16_384 * 12 * 20 / 1e6)


def test_table1_op_counts():
    assert cfar_op_counts("os", 176, 100) == [
        {"algorithm": "OS-CFAR", "add": 0, "cmp": 177, "total": 177},
        {"algorithm": "OS-CFAR (spiking)", "add": 176, "cmp": 100, "total": 276,
         "n_steps": 100}]
    ca = cfar_op_counts("ca", 176, 500)
    assert [(r["add"], r["cmp"], r["total"]) for r in ca] == [(176, 1, 177), (676, 500, 1176)]
    rows = graph_cfar_op_counts(Graph.from_yaml(CARRADA), {"det": 100})
    assert [(r["n_train"], r["total"]) for r in rows] == [(176, 177), (176, 276)]


def test_os_cfar_stage_matches_table3():
    (row,) = stage_rows(os_cfar_network())
    assert (row["node"], row["motif"], row["inputs"], row["neurons"], row["synapses"],
            row["time_steps"], row["repetitions"]) == ("det", "os_cfar", 16_384, 16_384,
                                                       2_899_968, 100, 1)
    assert row["synapses_stored"] == 177
    assert row["spikes_bound"] == 16_384 and row["synaptic_events_bound"] == 2_899_968


def test_range_fft_shaped_stage_reports_per_repetition():
    # Table 3 range-FFT: 512 inputs, 4 608 neurons, 37 888 synapses, 550 steps, 256 repetitions
    rng = np.random.default_rng(1)
    flat = rng.choice(512 * 4608, size=37_888, replace=False)
    rows, cols = np.divmod(flat, 4608)
    rows[:512] = np.arange(512)  # every input used
    net = SpikingNetwork(name="sft", n_steps=550, populations=[
        Population(id="x", shape={"rx": 4, "chirp": 64, "sample": 512}, source=True),
        Population(id="f", shape={"rx": 4, "chirp": 64, "n": 4608},
                   origin={"node": "rng", "motif": "sfft_radix4"})],
        projections=[MatrixProjection(id="w", source="x", target="f", contract=("sample",),
                                      produce=("n",), rows=rows, cols=cols,
                                      values=np.ones(rows.size), n_in_out=(512, 4608))],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=100, x_min=0.0, x_max=1.0))]).validate()
    (row,) = stage_rows(net)
    assert (row["inputs"], row["neurons"], row["synapses"], row["time_steps"],
            row["repetitions"]) == (512, 4608, 37_888, 550, 256)
    assert row["neurons_total"] == 4608 * 256


def test_measured_spikes_and_events():
    net = os_cfar_network(16, 32, k=40)
    x = np.random.default_rng(2).random((3, 16, 32))
    sim = simulate(net, {"det_in": x})
    (row,) = stage_rows(net, sim=sim)
    assert row["spikes_measured"] == sim.spike_counts["det"] / 3
    assert row["synaptic_events_measured"] == sim.synaptic_events["det_window"] / 3
    assert row["spikes_measured"] <= row["spikes_bound"]
