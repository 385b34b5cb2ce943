"""The multi-target tracker (radar.tracking) and the IR op ``track``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from compiler.chains_host import tracking_chain
from ir import Graph, evaluate
from ir.errors import IRError, RadarConfigError
from ir.ops import TRACK_STATE, Track
from ir.types import TensorType
from radar.config import RadarConfig, preset
from radar.scene import Scene, Target, simulate_frame
from radar.tracking import STATE, Tracker, track_sequence

COL = {name: k for k, name in enumerate(STATE)}


def _table(*rows: tuple[float, float], capacity: int = 4) -> np.ndarray:
    """A cluster table with the given (range_bin, doppler_bin) rows, then padding."""
    t = np.zeros((capacity, 5))
    for k, (r, d) in enumerate(rows):
        t[k] = [1.0, r, d, 1.0, 1.0]
    return t


# ------------------------------------------------------------------ hand-worked filter


def test_one_kalman_step_by_hand() -> None:
    # dt = 1, no process noise, R = I.  Birth x = (10, 1), P = I.  Predict x- = (11, 1),
    # P- = F F^T = [[2, 1], [1, 1]];  S = P- + I = [[3, 1], [1, 2]], S^-1 = [[2, -1], [-1, 3]]/5;
    # K = P- S^-1 = [[3, 1], [1, 2]]/5;  nu = (11.5, 1) - (11, 1) = (0.5, 0) -> K nu = (0.3, 0.1);
    # d^2 = nu^T S^-1 nu = 0.25 * 2/5 = 0.1.
    trk = Tracker(dt_s=1.0, accel_std_mps2=0.0, range_std_m=1.0, velocity_std_mps=1.0,
                  max_tracks=2)
    trk.update(_table((10.0, 1.0)))
    out = trk.update(_table((11.5, 1.0)))
    np.testing.assert_allclose(out[0, [COL["range_m"], COL["velocity_mps"]]], [11.3, 1.1])
    # Joseph form: (I - K) P- (I - K)^T + K K^T = [[3, 1], [1, 2]] / 5 (= (I - K) P-)
    np.testing.assert_allclose(trk.P[0], np.array([[3.0, 1.0], [1.0, 2.0]]) / 5, atol=1e-12)
    assert out[0, COL["hits"]] == 2 and out[1].tolist() == [0.0] * len(STATE)


def test_gate_rejects_a_far_measurement_and_opens_a_new_track() -> None:
    trk = Tracker(dt_s=1.0, accel_std_mps2=0.0, range_std_m=1.0, velocity_std_mps=1.0,
                  max_tracks=3)
    trk.update(_table((10.0, 0.0)))
    # predicted (10, 0), S = [[3, 1], [1, 2]]: a 4 m jump has d^2 = 16 * 2/5 = 6.4 <= 9.21,
    # a 5 m jump 25 * 2/5 = 10 > 9.21
    near = trk.update(_table((14.0, 0.0)))
    assert near[:, COL["id"]].tolist() == [1.0, 0.0, 0.0]
    far = Tracker(dt_s=1.0, accel_std_mps2=0.0, range_std_m=1.0, velocity_std_mps=1.0,
                  max_tracks=3)
    far.update(_table((10.0, 0.0)))
    out = far.update(_table((15.0, 0.0)))
    # the tentative track 1 missed (deleted), the far measurement is track 2 in slot 0
    assert out[:, COL["id"]].tolist() == [2.0, 0.0, 0.0]


def test_birth_confirmation_coasting_deletion_and_capacity() -> None:
    trk = Tracker(dt_s=0.1, confirm_hits=3, max_misses=2, max_tracks=2)
    seen = [trk.update(_table((5.0, 0.0), (20.0, 0.0), (40.0, 0.0)))]   # 3 births, 2 slots
    assert seen[0][:, COL["id"]].tolist() == [1.0, 2.0]                  # strongest rows first
    seen += [trk.update(_table((5.0, 0.0), (20.0, 0.0))) for _ in range(2)]
    assert seen[-1][:, COL["confirmed"]].tolist() == [1.0, 1.0]          # 3 hits
    assert seen[1][:, COL["confirmed"]].tolist() == [0.0, 0.0]
    coast = trk.update(_table((5.0, 0.0)))                               # track 2 misses once
    assert coast[1, [COL["valid"], COL["misses"]]].tolist() == [1.0, 1.0]
    gone = trk.update(_table((5.0, 0.0), (60.0, 0.0)))   # second miss: deleted; 60 m is born
    assert gone[:, COL["id"]].tolist() == [1.0, 3.0]
    assert gone[1, COL["confirmed"]] == 0.0
    # a tentative track dies at its first miss
    assert trk.update(_table((5.0, 0.0)))[1].tolist() == [0.0] * len(STATE)


def test_for_config_uses_bin_widths_and_zero_doppler() -> None:
    cfg = preset("carrada")
    trk = Tracker.for_config(cfg)
    out = trk.update(_table((100.0, 42.0)))
    assert out[0, COL["range_m"]] == pytest.approx(100 * cfg.range_resolution_m)
    assert out[0, COL["velocity_mps"]] == pytest.approx(10 * cfg.velocity_resolution_mps)
    assert trk.F[0, 1] == pytest.approx(0.1)


def test_bad_parameters_and_tables_raise() -> None:
    with pytest.raises(RadarConfigError, match="dt_s"):
        Tracker(dt_s=0.0)
    with pytest.raises(RadarConfigError, match="cluster table"):
        Tracker(dt_s=0.1).update(np.zeros((3, 4)))
    with pytest.raises(RadarConfigError, match="tables need shape"):
        track_sequence(np.zeros((3, 5)), dt_s=0.1)


@given(st.lists(st.lists(st.tuples(st.floats(0, 60), st.floats(0, 32)), max_size=5),
                min_size=1, max_size=12),
       st.integers(1, 5))
def test_track_tables_invariants(frames, max_tracks) -> None:
    tables = np.stack([_table(*rows, capacity=5) for rows in frames])
    params = {"dt_s": 0.1, "range_bin_m": 0.2, "velocity_bin_mps": 0.4,
              "doppler_zero_bin": 16, "max_tracks": max_tracks}
    out = track_sequence(tables, **params)
    assert out.shape == (len(frames), max_tracks, len(STATE))
    trk = Tracker(**params)
    np.testing.assert_array_equal(out, np.stack([trk.update(t) for t in tables]))
    valid = out[..., COL["valid"]] == 1
    assert (out[~valid] == 0).all()
    for k in range(len(frames)):
        ids = out[k, valid[k], COL["id"]]
        assert len(set(ids.tolist())) == len(ids) and (ids > 0).all()
    confirmed = out[..., COL["confirmed"]] == 1
    assert (out[confirmed][:, COL["hits"]] >= 3).all()
    # a slot's id never changes while it stays valid
    same = valid[1:] & valid[:-1]
    changed = out[1:, :, COL["id"]] != out[:-1, :, COL["id"]]
    assert not (same & changed & (out[1:, :, COL["hits"]] > 1)).any()


# ------------------------------------------------------------------ crossing targets


def _crossing_frames(cfg: RadarConfig, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """ADC frames of two targets crossing in range (10 -> 17.6 m at +4 m/s, 18 -> 10.4 at -4)."""
    cubes, truth = [], []
    for k in range(n_frames):
        t = k / cfg.frame_rate_hz
        targets = (Target(range_m=10 + 4 * t, velocity_mps=4.0, rcs_dbsm=5.0, name="a"),
                   Target(range_m=18 - 4 * t, velocity_mps=-4.0, rcs_dbsm=5.0, name="b"))
        cubes.append(simulate_frame(cfg, Scene(targets=targets), seed=k).adc)
        truth.append([(g.range_m, g.velocity_mps) for g in targets])
    return np.stack(cubes), np.array(truth)


def test_two_crossing_targets_are_tracked_through_the_crossing() -> None:
    base = preset("carrada")
    # 1 Tx x 1 Rx, 128 samples: dR = 0.40 m, dv = 0.845 m/s (keeps the test fast)
    cfg = RadarConfig(**{**base.model_dump(), "tx_positions_lambda": (0.0,),
                         "rx_positions_lambda": (0.0,), "n_samples": 128, "name": "small"})
    cubes, truth = _crossing_frames(cfg, 20)
    values = evaluate(tracking_chain(cfg, n_frames=20), {"adc": cubes})
    tracks = values["out"]
    assert tracks.shape == (20, 16, len(STATE))
    ids_seen = set()
    for k in range(20):
        live = tracks[k][tracks[k, :, COL["valid"]] == 1]
        if k >= 2:        # exactly two confirmed tracks from the third frame on (a noise
            live = live[live[:, COL["confirmed"]] == 1]    # detection may open a tentative one)
            assert len(live) == 2
        for target, (r_m, v_mps) in enumerate(truth[k]):
            # the targets share a range at the crossing: match them by velocity
            best = live[np.argmin(np.abs(live[:, COL["velocity_mps"]] - v_mps))]
            # bounds: a quarter of a range bin (0.40 m) and of a Doppler bin (0.845 m/s);
            # measured worst case 0.023 m and 0.027 m/s
            assert abs(best[COL["range_m"]] - r_m) <= 0.1
            assert abs(best[COL["velocity_mps"]] - v_mps) <= 0.2
            ids_seen.add((target, best[COL["id"]]))
    assert ids_seen == {(0, 1.0), (1, 2.0)}                # ids stable through the crossing


# ------------------------------------------------------------------ the IR op


def test_ir_track_type_checks_name_the_node() -> None:
    op = Track(dt_s=0.1, range_bin_m=0.2, velocity_bin_mps=0.4, doppler_zero_bin=16)
    good = TensorType(axes={"frame": 3, "cluster": 4, "feature": 5})
    assert op.infer("trk", [good]).axes == {"frame": 3, "track": 16, "state": len(TRACK_STATE)}
    bad = [TensorType(axes={"cluster": 4, "feature": 5}),
           TensorType(axes={"frame": 3, "cluster": 4, "feature": 6}),
           TensorType(axes={"frame": 3, "cluster": 4, "feature": 5}, domain="power"),
           TensorType(axes={"frame": 3, "doppler": 4, "range": 5}, domain="mask")]
    for t in bad:
        with pytest.raises(IRError, match="input must be a cluster table") as info:
            op.infer("trk", [t])
        assert info.value.node == "trk" and "node 'trk' (track)" in str(info.value)
    g = Graph.from_dict({"name": "t", "nodes": [
        {"id": "x", "op": "input", "shape": {"frame": 2, "range": 5}, "domain": "power"},
        {"id": "trk", "op": "track", "input": "x", "dt_s": 0.1, "range_bin_m": 1,
         "velocity_bin_mps": 1, "doppler_zero_bin": 0},
        {"id": "out", "op": "output", "input": "trk"}]})
    with pytest.raises(IRError, match="node 'trk' \\(track\\): input must be a cluster table"):
        g.verify()


def test_ir_track_evaluates_like_track_sequence() -> None:
    tables = np.stack([_table((10.0, 2.0)), _table((10.2, 2.0)), _table()])
    g = Graph.from_dict({"name": "t", "nodes": [
        {"id": "x", "op": "input", "shape": {"frame": 3, "cluster": 4, "feature": 5}},
        {"id": "trk", "op": "track", "input": "x", "dt_s": 0.1, "range_bin_m": 1.0,
         "velocity_bin_mps": 1.0, "doppler_zero_bin": 0, "max_tracks": 2},
        {"id": "out", "op": "output", "input": "trk"}]})
    out = evaluate(g, {"x": tables})["out"]
    np.testing.assert_array_equal(out, track_sequence(tables, dt_s=0.1, max_tracks=2))
    assert out[:, 0, COL["valid"]].tolist() == [1.0, 1.0, 0.0]   # tentative, then deleted
    assert TRACK_STATE == STATE


def test_the_example_chain_validates_with_the_preset_constants() -> None:
    from pathlib import Path

    g = Graph.from_yaml(Path(__file__).resolve().parents[1] / "examples" / "chains"
                        / "carrada_tracking.yaml")
    g.verify()
    cfg = preset("carrada")
    built = tracking_chain(cfg, n_frames=8).op("trk")
    assert g.op("trk").tracker_params() == built.tracker_params()
    assert dict(g.infer_types()["out"].axes) == {"frame": 8, "track": 16, "state": 7}
