"""Scene simulator: targets land on their ground-truth bins after a conventional numpy chain.

The chain here is deliberately independent of radar.dsp: hann window + FFT along samples
(positive half for real sampling), FFT along chirps + fftshift, magnitude, sum over rx.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ir.errors import RadarConfigError
from radar.config import RadarConfig, preset
from radar.scene import (
    Clutter,
    Leakage,
    Scene,
    Target,
    carrada_scene,
    seed003_scene,
    simulate_frame,
    target_amplitude_dbfs,
)

C = 299_792_458.0


def range_fft(adc: np.ndarray, iq: bool) -> np.ndarray:
    """Hann-windowed FFT along samples; real sampling keeps the positive half."""
    n = adc.shape[-1]
    spectrum = np.fft.fft(adc * np.hanning(n), axis=-1)
    return spectrum if iq else spectrum[..., : n // 2]


def rd_cube(adc: np.ndarray, iq: bool) -> np.ndarray:
    """Complex range-Doppler cube [rx, doppler (fftshifted), range]."""
    return np.fft.fftshift(np.fft.fft(range_fft(adc, iq), axis=1), axes=1)


def rd_map(adc: np.ndarray, iq: bool) -> np.ndarray:
    """|RD| summed over rx: [doppler, range]."""
    return np.abs(rd_cube(adc, iq)).sum(axis=0)


def circular_distance(a: int, b: int, n: int) -> int:
    d = abs(a - b) % n
    return min(d, n - d)


def only(scene: Scene, target: Target) -> Scene:
    """The scene's noise and gain with one target and nothing else."""
    return Scene(targets=(target,), noise_dbfs=scene.noise_dbfs, gain_dbfs=scene.gain_dbfs)


@pytest.mark.parametrize(("name", "make_scene"),
                         [("carrada", carrada_scene), ("seed003", seed003_scene)])
def test_each_target_alone_peaks_at_its_truth_bins(name, make_scene):
    cfg, scene = preset(name), make_scene()
    for target in scene.targets:
        frame = simulate_frame(cfg, only(scene, target), seed=3)
        (truth,) = frame.truth
        rd = rd_map(frame.adc, cfg.iq)
        d, r = np.unravel_index(np.argmax(rd), rd.shape)
        assert abs(int(r) - truth.range_bin) <= 1, (target.name, r, truth)
        assert circular_distance(int(d), truth.doppler_bin, cfg.n_chirps) <= 1, (target.name, d)
        # the peak stands well clear of the noise floor
        assert rd.max() > 30 * np.median(rd)


@pytest.mark.parametrize(("name", "make_scene"),
                         [("carrada", carrada_scene), ("seed003", seed003_scene)])
def test_full_scene_has_local_peaks_at_truth(name, make_scene):
    cfg = preset(name)
    frame = simulate_frame(cfg, make_scene(), seed=7)
    rd = rd_map(frame.adc, cfg.iq)
    floor = np.median(rd)
    m = cfg.n_chirps
    for truth in frame.truth:
        rows = np.arange(truth.doppler_bin - 3, truth.doppler_bin + 4) % m
        cols = np.arange(max(truth.range_bin - 3, 0), truth.range_bin + 4)
        window = rd[np.ix_(rows, cols)]
        i, j = np.unravel_index(np.argmax(window), window.shape)
        assert circular_distance(int(rows[i]), truth.doppler_bin, m) <= 1, truth
        assert abs(int(cols[j]) - truth.range_bin) <= 1, truth
        assert window.max() > 10 * floor, truth


def test_carrada_aliased_target_is_predicted():
    cfg = preset("carrada")
    frame = simulate_frame(cfg, carrada_scene(), seed=0)
    fast = next(t for t in frame.truth if t.name == "fast_car")
    assert fast.aliased and fast.velocity_mps < -cfg.max_velocity_mps
    # -20 m/s -> 2 v f_ctr n_tx T_c M / c = -47.64 bins from zero; +64 wraps to 48.36
    f_ctr = 77e9 + 29.3e12 * (4e-6 + 255 / 2 / 10e6)
    expected = 32 + 2 * -20.0 * f_ctr * 2 * 36e-6 * 64 / C + 64
    assert fast.doppler_bin_exact == pytest.approx(expected, rel=1e-12)
    assert fast.doppler_bin == 48
    assert [t.aliased for t in frame.truth] == [False, False, False, True]


def test_carrada_angle_fft_peaks_at_truth_angle():
    cfg = preset("carrada")
    n_angle = 64
    frame = simulate_frame(cfg, carrada_scene(), seed=1, n_angle_bins=n_angle)
    cube = rd_cube(frame.adc, cfg.iq)
    m, slots = cfg.n_chirps, np.repeat(np.arange(cfg.n_tx), cfg.n_rx)
    for truth in frame.truth:
        if truth.aliased:  # TDM compensation from the observed bin is ambiguous by 1/n_tx
            continue
        snapshot = cube[:, truth.doppler_bin, truth.range_bin]
        # Doppler phase per chirp period from the observed bin, removed per Tx slot
        cycles_per_tc = (truth.doppler_bin - m // 2) / (m * cfg.n_tx)
        snapshot = snapshot * np.exp(-2j * np.pi * slots * cycles_per_tc)
        spectrum = np.abs(np.fft.fftshift(np.fft.fft(snapshot, n_angle)))
        peak = int(np.argmax(spectrum))
        assert truth.angle_bin is not None
        assert circular_distance(peak, truth.angle_bin, n_angle) <= 1, (truth.name, peak)
    # hand check: 20 deg on a lambda/2 array -> 64 * 0.5 * sin(20 deg) = 10.94 -> 32 + 11
    assert frame.truth[0].angle_bin == 43


def test_exact_bins_match_zero_padded_spectral_peaks():
    # noise-free fast car: range-Doppler coupling moves its range peak by -0.49 bins and the
    # sampled-band centre frequency moves its Doppler peak by 0.3 bins; truth must follow
    cfg = preset("carrada")
    target = carrada_scene().targets[-1]
    frame = simulate_frame(cfg, Scene(targets=(target,), noise_dbfs=None, quantize=False),
                           seed=0)
    (truth,) = frame.truth
    pad = 32
    n, m = cfg.n_samples, cfg.n_chirps
    spectrum = np.abs(np.fft.fft(frame.adc * np.hanning(n), n * pad, axis=-1)).sum(axis=(0, 1))
    assert np.argmax(spectrum) / pad == pytest.approx(truth.range_bin_exact, abs=1.5 / pad)
    assert truth.range_bin_exact == pytest.approx(200.16 - 0.23 - 0.26, abs=0.02)
    column = np.fft.fft(frame.adc * np.hanning(n), axis=-1)[:, :, truth.range_bin]
    doppler = np.abs(np.fft.fftshift(np.fft.fft(column, m * pad, axis=1), axes=1)).sum(axis=0)
    assert np.argmax(doppler) / pad == pytest.approx(truth.doppler_bin_exact, abs=1.5 / pad)


def test_same_seed_same_cube_different_seed_different_noise():
    cfg = preset("carrada")
    a = simulate_frame(cfg, carrada_scene(), seed=11)
    b = simulate_frame(cfg, carrada_scene(), seed=11)
    c = simulate_frame(cfg, carrada_scene(), seed=12)
    np.testing.assert_array_equal(a.adc, b.adc)
    assert not np.array_equal(a.adc, c.adc)
    assert a.truth == c.truth
    # noise alone also changes with the seed
    quiet = Scene(targets=carrada_scene().targets, noise_dbfs=-80.0)
    assert not np.array_equal(simulate_frame(cfg, quiet, seed=1).adc,
                              simulate_frame(cfg, quiet, seed=2).adc)


def test_layout_dtype_and_read_only():
    f = simulate_frame(preset("carrada"), carrada_scene(), seed=0)
    assert f.adc.shape == (8, 64, 256) and f.adc.dtype == np.complex128
    g = simulate_frame(preset("seed003"), seed003_scene(), seed=0)
    assert g.adc.shape == (1, 128, 1024) and g.adc.dtype == np.float64
    assert not f.adc.flags.writeable
    assert (f.seed, f.config.name, f.scene.name) == (0, "carrada", "carrada")
    assert g.truth[0].angle_bin is None  # a single channel has no angle axis


def test_quantised_output_is_integer_codes_within_full_scale():
    cfg = preset("seed003")
    loud = Scene(leakage=(Leakage(range_m=0.0, amplitude_dbfs=6.0),), noise_dbfs=-60.0)
    frame = simulate_frame(cfg, loud, seed=0)
    fs = cfg.full_scale_code  # 2048 for 12 bits
    assert fs == 2048
    np.testing.assert_array_equal(frame.adc, np.rint(frame.adc))
    assert frame.adc.min() >= -fs and frame.adc.max() <= fs - 1
    # a +6 dBFS DC line (1.995 FS) clips every sample: cos(2 pi * 0) = 1 at range 0
    assert frame.n_clipped == frame.adc.size
    assert set(np.unique(frame.adc)) == {fs - 1.0}
    assert simulate_frame(cfg, seed003_scene(), seed=0).n_clipped == 0


def _tiny(**overrides) -> RadarConfig:
    """A hand-workable sensor: lambda = 1 m, 2S/c = 1e6 /(m s), fs = 1 MHz -> R cycles/sample."""
    kw = dict(carrier_hz=C, slope_hz_per_s=C / 2 * 1e6, fs_hz=1e6, n_samples=8, n_chirps=4,
              chirp_period_s=10e-6, adc_bits=16)
    kw.update(overrides)
    return RadarConfig(**kw)


def test_hand_worked_samples():
    cfg = _tiny()
    # R0 = 0.25 m, v = 0: phase = R*t_n*1e6 + 2R = 0.25 n + 0.5 cycles -> -1, -j, 1, j, ...
    # |a| = FS * 10^(gain/20) * sqrt(sigma) / R^2 = 32768 * 0.01 * 1 / 0.0625 = 5242.88
    scene = Scene(targets=(Target(range_m=0.25),), gain_dbfs=-40.0, noise_dbfs=None,
                  quantize=False)
    adc = simulate_frame(cfg, scene, seed=0).adc
    expected = 5242.88 * np.array([-1, -1j, 1, 1j, -1, -1j, 1, 1j])
    np.testing.assert_allclose(adc[0, 0], expected, atol=1e-8)
    np.testing.assert_allclose(adc[0, 3], expected, atol=1e-8)  # static: every chirp alike
    assert target_amplitude_dbfs(0.0, 0.25, -40.0) == pytest.approx(20 * np.log10(0.16))


def test_tdm_slot_phase_matches_model():
    # two Tx (0 and 3 lambda), one Rx; slot 1 fires T_c after slot 0 in the same loop
    cfg = _tiny(tx_positions_lambda=(0.0, 3.0), n_chirps=2, carrier_hz=77e9,
                slope_hz_per_s=30e12, fs_hz=10e6)
    v, az = 5.0, 12.0
    scene = Scene(targets=(Target(range_m=2.0, velocity_mps=v, azimuth_deg=az),),
                  noise_dbfs=None, quantize=False)
    adc = simulate_frame(cfg, scene, seed=0).adc
    t_n = np.arange(8) / 10e6
    # extra cycles of slot 1: 3 sin(az) + (2 v T_c / c) (f_c + S t_n), from R(t) = R0 + v t
    cycles = 3 * np.sin(np.deg2rad(az)) + 2 * v * 10e-6 / C * (77e9 + 30e12 * t_n)
    ratio = adc[1, 0] / adc[0, 0]
    np.testing.assert_allclose(ratio, np.exp(2j * np.pi * cycles), atol=1e-9)


def test_real_sampling_is_the_real_part_of_iq():
    scene = Scene(targets=(Target(range_m=20.0, velocity_mps=3.0, azimuth_deg=5.0),
                           Target(range_m=12.0, velocity_mps=-2.0, rcs_dbsm=6.0)),
                  noise_dbfs=None, quantize=False)
    iq = simulate_frame(preset("carrada"), scene, seed=0).adc
    real_cfg = RadarConfig(**{**preset("carrada").model_dump(), "iq": False})
    real = simulate_frame(real_cfg, scene, seed=0).adc
    np.testing.assert_array_equal(real, iq.real)


def test_superposition_without_noise_and_adc():
    cfg = preset("carrada")
    t1 = Target(range_m=10.0, velocity_mps=2.0, azimuth_deg=-15.0)
    t2 = Target(range_m=33.0, velocity_mps=-6.0, azimuth_deg=40.0, rcs_dbsm=8.0)
    both = Scene(targets=(t1, t2), noise_dbfs=None, quantize=False)
    one = [Scene(targets=(t,), noise_dbfs=None, quantize=False) for t in (t1, t2)]
    total = simulate_frame(cfg, both, seed=0).adc
    parts = sum(simulate_frame(cfg, s, seed=0).adc for s in one)
    np.testing.assert_allclose(total, parts, rtol=0, atol=1e-9 * np.abs(total).max())


SMALL = RadarConfig(carrier_hz=77e9, slope_hz_per_s=20e12, fs_hz=10e6, n_samples=64,
                    n_chirps=32, chirp_period_s=20e-6, tx_positions_lambda=(0.0, 1.0),
                    rx_positions_lambda=(0.0, 0.5))


@given(range_frac=st.floats(0.05, 0.9), velocity_frac=st.floats(-3.0, 3.0),
       azimuth=st.floats(-60.0, 60.0))
def test_any_single_target_peaks_at_truth(range_frac, velocity_frac, azimuth):
    v = velocity_frac * SMALL.max_velocity_mps  # up to 3x beyond v_max: aliasing included
    target = Target(range_m=range_frac * SMALL.max_range_m, velocity_mps=v, azimuth_deg=azimuth)
    frame = simulate_frame(SMALL, Scene(targets=(target,), noise_dbfs=None, quantize=False),
                           seed=0)
    (truth,) = frame.truth
    rd = rd_map(frame.adc, True)
    d, r = np.unravel_index(np.argmax(rd), rd.shape)
    assert circular_distance(int(r), truth.range_bin, SMALL.n_samples) <= 1
    assert circular_distance(int(d), truth.doppler_bin, SMALL.n_chirps) <= 1
    assert truth.aliased == (not -SMALL.max_velocity_mps <= v < SMALL.max_velocity_mps)


def test_seed003_frame_simulates():
    # its speed (under 1 s) is a benchmark claim: benchmarks/speed_claims.py prints it
    cfg, scene = preset("seed003"), seed003_scene()
    frame = simulate_frame(cfg, scene, seed=0)
    assert frame.adc.shape == (cfg.n_virtual, cfg.n_chirps, cfg.n_samples)
    assert len(frame.truth) == len(scene.targets)


@pytest.mark.parametrize(
    ("scene", "seed", "pattern"),
    [
        (Scene(targets=(Target(range_m=60.0, name="far"),)), 0,
         r"target 0 \('far'\).*outside \(0, 51\.16\] m.*config 'carrada'"),
        (Scene(targets=(Target(range_m=0.01, velocity_mps=-5.0),)), 0, r"to -0\.01\d* m"),
        (Scene(clutter=Clutter(amplitude_dbfs=-70, max_range_m=80.0)), 0,
         r"clutter range 80 m exceeds max_range_m = 51\.16"),
        (Scene(), -1, r"seed must be a non-negative int, got -1"),
        (Scene(), True, r"seed must be a non-negative int, got True"),
    ],
)
def test_bad_scene_or_seed_raises(scene, seed, pattern):
    with pytest.raises(RadarConfigError, match=pattern):
        simulate_frame(preset("carrada"), scene, seed=seed)


def test_bad_records_raise_radar_config_error():
    with pytest.raises(RadarConfigError, match=r"field 'range_m' = 0\.0: .*greater than 0"):
        Target(range_m=0.0)
    with pytest.raises(RadarConfigError, match=r"field 'azimuth_deg' = 95"):
        Target(range_m=1.0, azimuth_deg=95)
    with pytest.raises(RadarConfigError, match=r"min_range_m = 9 m must be below"):
        Clutter(amplitude_dbfs=-70, min_range_m=9.0, max_range_m=5.0)
    with pytest.raises(RadarConfigError, match=r"Target: field 'speed' = 1\.0: Extra"):
        Scene(targets=[{"range_m": 3.0, "speed": 1.0}])
