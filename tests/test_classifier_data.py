"""Class signatures, direct RD-map synthesis (checked against the full ADC model), ROI dataset."""

from __future__ import annotations

import numpy as np
import pytest

from radar.config import preset
from radar.roi_dataset import (
    db_above_noise,
    extract_rois,
    make_dataset,
    noise_floor,
    point_bins,
    synthesize_rd,
)
from radar.scene import Scene, simulate_frame
from radar.signatures import ObjectState, Scatterers, random_object, scatterers, to_targets
from radar.spectra import range_doppler_map
from radar.windows import apply_window

CFG = preset("carrada")


def test_pedestrian_limbs_swing_around_the_torso() -> None:
    ped = ObjectState(kind="pedestrian", range_m=10.0, speed_mps=1.5, rate_hz=1.0)
    v = np.array([scatterers(ped, t).velocity_mps for t in np.linspace(0, 1, 21)])
    assert np.allclose(v[:, 0], 1.5)  # torso
    feet = v[:, -2:]
    # foot: s (1 + sin(.)): between 0 and 2 s over a cycle
    assert feet.min() == pytest.approx(0.0, abs=0.05) and feet.max() == pytest.approx(3.0,
                                                                                        abs=0.05)


def test_heading_projects_speed_and_extent() -> None:
    car = ObjectState(kind="car", range_m=20.0, speed_mps=10.0, heading_deg=180.0,
                      length_m=4.0)
    pts = scatterers(car, 0.5)
    assert car.radial_velocity_mps == pytest.approx(-10.0)
    assert np.allclose(pts.velocity_mps[:8], -10.0)
    assert pts.range_m[:8].max() - pts.range_m[:8].min() == pytest.approx(4.0)
    assert pts.range_m[0] == pytest.approx(20.0 - 5.0 - 2.0)  # front bumper, 0.5 s later


def test_synthesis_matches_the_full_adc_chain_on_a_point() -> None:
    pts = Scatterers(np.array([12.3]), np.array([3.1]), np.array([10.0]), np.array([0.0]))
    scene = Scene(targets=to_targets(pts), noise_dbfs=None, quantize=False)
    adc = apply_window(simulate_frame(CFG, scene, seed=0).adc, "hann", axis=1)  # the chain's
    full = range_doppler_map(adc, magnitude="square")  # Doppler window + range window
    fast = synthesize_rd(CFG, pts, np.random.default_rng(0), noise_dbfs=-400.0).T
    peak = np.unravel_index(full.argmax(), full.shape)
    assert np.unravel_index(fast.argmax(), fast.shape) == peak
    # range migration and the TDM slot phase are left out: < 0.5 dB at the peak
    assert abs(10 * np.log10(fast[peak] / full[peak])) < 0.5
    near = full > full.max() * 1e-3
    assert np.allclose(10 * np.log10(fast[near] / full[near]), 0.0, atol=1.0)


def test_noise_floor_is_the_map_median() -> None:
    empty = Scatterers(*(np.zeros(0) for _ in range(4)))
    rd = synthesize_rd(CFG, empty, np.random.default_rng(3), noise_dbfs=-66.0)
    assert abs(10 * np.log10(np.median(rd) / noise_floor(CFG, -66.0))) < 0.1
    assert abs(np.median(db_above_noise(rd))) < 1e-9


def test_point_bins_agree_with_the_scene_truth() -> None:
    pts = Scatterers(np.array([8.0, 30.0]), np.array([-1.5, 20.0]), np.zeros(2), np.zeros(2))
    truth = simulate_frame(CFG, Scene(targets=to_targets(pts), noise_dbfs=None), seed=0).truth
    r, d = point_bins(CFG, pts.range_m, pts.velocity_mps)
    assert np.allclose(r, [t.range_bin_exact for t in truth])
    assert np.allclose(d, [t.doppler_bin_exact for t in truth])


def test_extract_rois_wraps_doppler_and_fills_range() -> None:
    maps = np.arange(2 * 4 * 5, dtype=float).reshape(2, 4, 5)  # frame, doppler 4, range 5
    rois = extract_rois(maps, np.array([[[4, 0], [0, 3]]]), (3, 2), fill=-1.0)
    # frame 0: range 3..5 (5 is beyond), doppler -1..0 -> 3, 0
    assert rois[0, 0].tolist() == [[18.0, 3.0], [19.0, 4.0], [-1.0, -1.0]]
    # frame 1: range -1..1, doppler 2..3
    assert rois[0, 1].tolist() == [[-1.0, -1.0], [30.0, 35.0], [31.0, 36.0]]


def test_dataset_is_seeded_split_by_scene_and_varied() -> None:
    a = make_dataset(12, seed=5, roi_shape=(16, 8), n_frames=3)
    b = make_dataset(12, seed=5, roi_shape=(16, 8), n_frames=3)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.y, b.y)
    assert a.x.shape[1:] == (3, 16, 8)
    for scene in np.unique(a.meta["scene"]):
        assert len(set(a.split[a.meta["scene"] == scene])) == 1
    assert set(a.meta["n_objects"]) <= {1, 2, 3} and len(set(a.y)) == 3
    assert np.ptp(a.meta["range_m"]) > 10 and np.ptp(a.meta["noise_dbfs"]) > 5
    # each ROI is centred on its object: the centre region is well above the noise
    assert np.median(a.x[:, :, 6:10, 2:6].max(axis=(2, 3))) > 15.0
    c = make_dataset(13, seed=5, roi_shape=(16, 8), n_frames=3)  # one more scene, same start
    assert np.array_equal(c.x[: len(a.y)], a.x)


def test_random_objects_stay_near_radial() -> None:
    rng = np.random.default_rng(0)
    for kind in ("car", "pedestrian", "cyclist"):
        for _ in range(20):
            o = random_object(kind, rng)
            assert abs(o.radial_velocity_mps) >= 0.5 * o.speed_mps - 1e-9
