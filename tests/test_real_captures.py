"""Compiled chains on the real captures shipped in radar/data agree with the conventional chains.

* TI chirps (``ti_chirps/data_tum.npy``, 4 real chirps × 1024 samples): the compiled 1-D range
  chain (examples/chains/ti_range.yaml: range S-FT → |X| → OS-CFAR, for loihi2) finds the
  annotated reflections (data README) that the conventional chain finds, within ± 1 bin.
* OpenRadar (``openradar/simple_frame_1.npy``, decoded, chirp means removed as its README says):
  the compiled 2-D chain's RD map and OS-CFAR detections against the conventional ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.reference import run_program
from compiler import compile_graph
from compiler.chains import capture_chain
from compiler.lowering.dft_common import modulus_rmse
from ir import Graph, evaluate
from radar.loaders import load_openradar, load_ti_chirps
from radarsnn.demo.matching import score_peaks

ROOT = Path(__file__).resolve().parents[1]

#: Annotated reflections per chirp (range-FFT bins), from the data README.
ANNOTATED = {0: [25, 201], 1: [404], 2: [42, 66], 3: [1, 39, 87, 127]}


def _near(bins, found) -> bool:
    return any(abs(int(b) - int(f)) <= 1 for f in found for b in [bins])


@pytest.fixture(scope="module")
def ti(shared_data):
    chirps, _ = load_ti_chirps(shared_data)
    return chirps, Graph.from_yaml(ROOT / "examples" / "chains" / "ti_range.yaml")


def test_ti_chirps_calibrated_on_the_capture_match_the_conventional_detections(ti):
    chirps, graph = ti
    program = compile_graph(graph, "loihi2", calibration_inputs={"chirp": chirps})
    for i, chirp in enumerate(chirps):
        spiking = np.flatnonzero(run_program(program, {"chirp": chirp}).outputs["out"])
        conv = evaluate(graph, {"chirp": chirp})
        conventional = np.flatnonzero(conv["out"])
        # identical detection sets but for cells whose conventional CFAR decision is within
        # 5 % of its threshold (the S-FT's error at T = 256 is ~1 % rms of the spectrum and
        # larger on the small training cells; measured: one cell, chirp 0 bin 225, at 2.8 %)
        marginal = set(_marginal_cells(np.abs(conv["mag"]), 0.05).tolist())
        assert set(spiking.tolist()) ^ set(conventional.tolist()) <= marginal, i
        assert len(set(spiking.tolist()) ^ set(conventional.tolist())) <= 1, i
        for b in ANNOTATED[i]:
            if _near(b, conventional):
                assert _near(b, spiking), (i, b)


def _marginal_cells(m: np.ndarray, margin: float) -> np.ndarray:
    """Bins whose OS-CFAR ratio x_CUT / (α x_(k)) of ti_range.yaml is within ``margin`` of 1."""
    guard, train, k, alpha = 2, 12, 18, 6.0
    out = []
    for i in range(m.size):
        cells = np.r_[m[max(0, i - guard - train):max(0, i - guard)],
                      m[i + guard + 1:i + guard + train + 1]]
        kk = min(len(cells), max(1, int(np.ceil(k * len(cells) / (2 * train)))))
        kth = np.sort(cells)[::-1][kk - 1]
        if kth > 0 and abs(m[i] / (alpha * kth) - 1) < margin:
            out.append(i)
    return np.array(out, dtype=int)


@pytest.mark.parametrize("i", range(4))
def test_ti_chirps_leave_one_out_find_the_annotated_reflections(ti, i):
    chirps, graph = ti
    others = np.delete(chirps, i, axis=0)  # calibrated without the chirp under test
    program = compile_graph(graph, "loihi2", calibration_inputs={"chirp": others})
    # chirp 0 is stronger than the other three (a third of its samples exceed their range)
    result = run_program(program, {"chirp": chirps[i]}, out_of_range="clip")
    spiking = np.flatnonzero(result.outputs["out"])
    conventional = np.flatnonzero(evaluate(graph, {"chirp": chirps[i]})["out"])
    required = [b for b in ANNOTATED[i] if _near(b, conventional)]
    assert required or i == 1  # chirp 1's weak far target is below the conventional CFAR too
    assert all(_near(b, spiking) for b in required), (required, spiking.tolist())


def _openradar_chain() -> Graph:
    return capture_chain()


@pytest.mark.parametrize(("target", "min_precision"), [(None, 0.97), ("loihi2", 0.97)])
def test_openradar_frame_rd_map_and_detections_agree(shared_data, target, min_precision):
    frame = load_openradar("simple_frame_1", shared_data)
    frame = frame - frame.mean(axis=1, keepdims=True)
    graph = _openradar_chain()
    conv = evaluate(graph, {"frame": frame})
    program = compile_graph(graph, target, calibration_inputs={"frame": frame})
    values = run_program(program, {"frame": frame}).values
    spk_map, conv_map = np.asarray(values["mag"]).T, conv["mag"].T  # [range, doppler]
    # measured: RMSE 3.6e-5 (no target) / 9.7e-5 (loihi2, 8-bit weights)
    assert modulus_rmse(spk_map, conv_map, drop_bin0=False) < 2e-4
    s, c = values["det"].T, conv["det"].T
    hits = int((s & c).sum())
    # measured before the chip dynamic-range work: precision 0.718 on loihi2 (the OS-CFAR's
    # CUT weight k + 1/2 clipped to the 8-bit scale); the CUT weight is now k, exact
    assert hits / c.sum() >= 0.97 and hits / s.sum() >= min_precision
    named = [(107, 64), (1, 64), (41, 64)]  # strongest reflections (data README), zero Doppler
    assert None not in score_peaks(c, conv_map, named).found
    assert None not in score_peaks(s, spk_map, named).found


def test_openradar_captures_calibrated_on_each_other_keep_the_detections(shared_data):
    """The same TI sensor, two captures: each compiled for loihi2 on the *other* capture
    (raw frames: the static split removes the chirp means on the host). Measured: cell
    sensitivity / precision 0.984 / 0.970 and 0.990 / 0.981 (pooled 0.986 / 0.974); before
    the static split, with per-bin gains calibrated on the other capture, 0.88-0.91."""
    frames = [load_openradar("simple_frame_1", shared_data),
              load_openradar("doppler_example", shared_data)[:, :128]]
    graph = _openradar_chain()
    hits = conv_cells = spk_cells = 0
    for cal, test in ((frames[1], frames[0]), (frames[0], frames[1])):
        program = compile_graph(graph, "loihi2", calibration_inputs={"frame": cal})
        c = evaluate(graph, {"frame": test})["det"]
        s = np.asarray(run_program(program, {"frame": test}, out_of_range="clip")
                       .values["det"]).astype(bool)
        hits, conv_cells, spk_cells = hits + int((c & s).sum()), conv_cells + c.sum(), \
            spk_cells + s.sum()
    assert hits >= 0.97 * conv_cells and hits >= 0.97 * spk_cells, (hits, conv_cells, spk_cells)
