"""Sweep metrics and costs: hand-worked counts, additivity over slices, the Pareto front."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from compiler.lowering.dft_common import sft_rmse
from ir.errors import CompileError, SimulationError
from radar.scene import TargetTruth
from radarsnn.sweep.cost import finalize_cost
from radarsnn.sweep.figures import draw_figures, pareto_front
from radarsnn.sweep.metrics import (
    FrameData,
    Metric,
    MetricRegistry,
    default_metrics,
    detection_counts,
    sensitivity_precision,
)
from radarsnn.sweep.sections import FigureSpec

REG = default_metrics()


def _truth(r, d):
    return TargetTruth(name="t", range_m=1.0, velocity_mps=0.0, azimuth_deg=0.0, rcs_dbsm=0.0,
                       amplitude_dbfs=0.0, range_bin=r, range_bin_exact=float(r), doppler_bin=d,
                       doppler_bin_exact=float(d), aliased=False, angle_bin=None)


def test_cfar_counts_hand_worked():
    s = np.array([[1, 1, 0], [0, 1, 0]], float)   # spiking decisions
    c = np.array([[1, 0, 1], [0, 1, 1]], bool)     # conventional
    got = REG["cfar"].update(FrameData(values={"d": s}, reference={"d": c}, node="d"))
    assert got == {"tp": 2, "fn": 2, "fp": 1}
    fin = REG["cfar"].finalize(got)
    assert (fin["sensitivity"], fin["precision"]) == (0.5, 2 / 3)


def test_empty_denominators_are_perfect():
    assert sensitivity_precision(tp=0, fn=0, fp=0) == (1.0, 1.0)
    assert sensitivity_precision(tp=0, fn=2, fp=0) == (0.0, 1.0)


def test_detection_against_truth_wraps_doppler_and_clips_range():
    det = np.zeros((10, 6), bool)
    det[0, 5] = True      # near the target at (1, 0): Doppler 5 wraps to -1
    det[9, 2] = True      # near (9, 3): range 10 is clipped, not wrapped to 0
    det[5, 3] = True      # a false alarm
    assert detection_counts(det, np.array([[1, 0], [9, 3], [4, 0]]), 1) == (2, 3, 2)
    frame = FrameData(values={"m": det}, reference={"m": det.T.copy().T}, node="m",
                      axes=("range", "doppler"), truth=(_truth(1, 0), _truth(9, 3), _truth(4, 0)))
    sums = REG["detection"].update(frame)
    fin = REG["detection"].finalize(sums)
    assert fin["pd"] == pytest.approx(2 / 3) and fin["false_alarms_per_frame"] == 1.0
    flipped = FrameData(values={"m": det.T}, reference={"m": det.T}, node="m",
                        axes=("doppler", "range"), truth=frame.truth)
    assert REG["detection"].update(flipped) == sums
    with pytest.raises(SimulationError, match=r"node 'm' has axes \['x'\]"):
        REG["detection"].update(FrameData(values={"m": det[0]}, reference={"m": det[0]},
                                          node="m", axes=("x",)))


@given(arrays(np.bool_, (6, 5)), arrays(np.bool_, (6, 5)), st.integers(0, 2))
def test_detection_counts_match_a_brute_force(det, mask, tol):
    bins = np.argwhere(mask)[:4]
    hits, n, near = detection_counts(det, bins, tol)
    close = np.zeros_like(det)
    got_hits = 0
    for r, d in bins:
        box = [(rr, dd % 5) for rr in range(r - tol, r + tol + 1) if 0 <= rr < 6
               for dd in range(d - tol, d + tol + 1)]
        got_hits += any(det[b] for b in box)
        for b in box:
            close[b] = True
    assert (hits, n, near) == (got_hits, int(det.sum()), int((det & close).sum()))


def test_sft_rmse_metric_is_the_protocol_averaged_over_frames():
    rng = np.random.default_rng(0)
    refs = [np.fft.fft(rng.normal(size=16)) for _ in range(3)]
    ys = [r + 0.1 * rng.normal(size=16) for r in refs]
    total = {}
    for y, r in zip(ys, refs, strict=True):
        for k, v in REG["sft_rmse"].update(FrameData({"f": y}, {"f": r}, "f")).items():
            total[k] = total.get(k, 0) + v
    assert REG["sft_rmse"].finalize(total)["rmse"] == pytest.approx(
        np.mean([sft_rmse(y, r) for y, r in zip(ys, refs, strict=True)]), rel=1e-12)


def test_classifier_accuracy_hook():
    m = REG["classifier_accuracy"]
    one = m.update(FrameData({"c": np.array([0.1, 0.7, 0.2])}, {}, "c", label=1))
    two = m.update(FrameData({"c": np.array([0.9, 0.0, 0.2])}, {}, "c", label=2))
    assert m.finalize({k: one[k] + two[k] for k in one}) == {"accuracy": 0.5}
    with pytest.raises(SimulationError, match=r"no labels \(node 'c'\)"):
        m.update(FrameData({"c": np.zeros(3)}, {}, "c"))


@given(st.lists(st.tuples(arrays(np.bool_, 12), arrays(np.bool_, 12)), min_size=1,
                max_size=8), st.integers(1, 8))
def test_cfar_sums_over_slices_equal_the_pooled_counts(frames, cut):
    def total(chunk):
        out = {}
        for s, c in chunk:
            for k, v in REG["cfar"].update(FrameData({"d": s}, {"d": c}, "d")).items():
                out[k] = out.get(k, 0) + v
        return out

    a, b = total(frames[:cut]), total(frames[cut:])
    merged = {k: a.get(k, 0) + b.get(k, 0) for k in ("tp", "fn", "fp")}
    s = np.concatenate([f[0] for f in frames])
    c = np.concatenate([f[1] for f in frames])
    assert merged == {"tp": int((s & c).sum()), "fn": int((~s & c).sum()),
                      "fp": int((s & ~c).sum())}


def test_registry_errors_and_replacement():
    reg = MetricRegistry()
    m = Metric("x", lambda f: {"n": 1}, lambda s: s)
    reg.register(m)
    with pytest.raises(SimulationError, match=r"'x' is already registered"):
        reg.register(m)
    reg.register(Metric("x", lambda f: {"n": 2}, lambda s: s), replace=True)
    assert reg["x"].update(None) == {"n": 2}
    with pytest.raises(SimulationError, match=r"metric 'y' is not registered; known: \['x'\]"):
        reg["y"]  # noqa: B018


def test_cost_per_frame():
    assert finalize_cost({"spikes": 7, "synaptic_events": 10, "clipped": 3, "frames": 2}) == {
        "spikes_per_frame": 3.5, "synaptic_events_per_frame": 5.0, "clipped_per_frame": 1.5,
        "frames": 2}


@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5)), min_size=1, max_size=12))
def test_pareto_front_matches_the_definition(points):
    cost, value = zip(*points, strict=True)
    front = pareto_front(cost, value)
    dominated = [any(c2 <= c and v2 >= v and (c2, v2) != (c, v) for c2, v2 in points)
                 for c, v in points]
    # every kept point is undominated, and every undominated (cost, value) pair is kept once
    assert all(not dominated[i] for i in front)
    assert {points[i] for i in front} == {p for p, d in zip(points, dominated, strict=True)
                                         if not d}
    assert [cost[i] for i in front] == sorted(cost[i] for i in front)
    low = pareto_front(cost, value, maximize=False)
    assert {points[i] for i in low} == {p for p in points if not any(
        c2 <= p[0] and v2 <= p[1] and (c2, v2) != p for c2, v2 in points)}


def test_figures_are_drawn_and_name_missing_metrics(tmp_path):
    rows = [{"point": f"p{t}{c}", "params": {"chain": c, "time_steps": t}, "complete": True,
             "error": None,
             "metrics": {"cfar": {"sensitivity": 1 - 1 / t, "precision": 1 - 2 / t},
                         "sft": {"rmse": 1 / t}},
             "cost": {"synapses": 10 * t, "steps": t}}
            for t in (10, 100, 1000) for c in ("os", "ca")]
    figs = [FigureSpec.model_validate(f) for f in
            ("fig7", {"kind": "pareto", "metric": "cfar.precision", "cost": "steps"},
             {"kind": "sft_rmse", "metric": "sft.rmse", "name": "rmse_vs_t"})]
    paths = draw_figures(figs, rows, tmp_path, {"cfar": "cfar", "sft": "sft_rmse"})
    assert [p.name for p in paths] == ["fig7.png", "pareto.png", "rmse_vs_t.png"]
    assert all(p.read_bytes()[:4] == b"\x89PNG" for p in paths)
    with pytest.raises(CompileError, match=r"metric 'nope' is not in the sweep's metrics"):
        draw_figures([FigureSpec(kind="pareto", metric="nope.x")], rows, tmp_path,
                     {"cfar": "cfar"})
    with pytest.raises(CompileError, match=r"has no sft_rmse metric"):
        draw_figures([FigureSpec(kind="sft_rmse")], rows, tmp_path, {"cfar": "cfar"})
