"""RadarConfig: hand-computed derived quantities of the presets, validation, invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ir.errors import RadarConfigError
from radar.config import PRESETS, SPEED_OF_LIGHT_MPS, RadarConfig, preset

C = 299_792_458.0


def _base(**overrides) -> dict:
    kw = dict(carrier_hz=77e9, slope_hz_per_s=30e12, fs_hz=10e6, n_samples=256, n_chirps=64,
              chirp_period_s=40e-6)
    kw.update(overrides)
    return kw


def test_carrada_derived_by_hand():
    cfg = preset("carrada")
    # B_s = 29.3 MHz/us * 256 / 10 Msps = 29.3e12 * 25.6e-6 = 750.08 MHz
    assert cfg.sampled_bandwidth_hz == pytest.approx(750.08e6, rel=1e-12)
    # dR = c / (2 * 750.08 MHz) = 299792458 / 1.50016e9
    assert cfg.range_resolution_m == pytest.approx(0.1998403224, rel=1e-9)
    # IQ: 256 bins * dR = fs c / (2 S) = 1e7 * c / 5.86e13
    assert cfg.max_range_m == pytest.approx(51.1591225256, rel=1e-9)
    assert cfg.n_range_bins == 256
    # lambda = c / 77 GHz = 3.8934085 mm; dv = lambda / (2 * 2 * 64 * 36 us) = lambda / 9.216 ms
    assert cfg.wavelength_m == pytest.approx(3.8934085455e-3, rel=1e-9)
    assert cfg.velocity_resolution_mps == pytest.approx(0.4224618647, rel=1e-9)
    # v_max = lambda / (4 * 2 * 36 us) = lambda / 288 us
    assert cfg.max_velocity_mps == pytest.approx(13.5187796717, rel=1e-9)
    assert (cfg.n_tx, cfg.n_rx, cfg.n_virtual) == (2, 4, 8)
    assert cfg.frame_time_s == pytest.approx(2 * 64 * 36e-6)


def test_seed003_derived_by_hand():
    cfg = preset("seed003")
    assert cfg.sampled_bandwidth_hz == pytest.approx(275e6, rel=1e-12)
    # dR = c / 550 MHz = 0.54508 m; real sampling: 512 bins -> 279.08 m ("up to ~280 m")
    assert cfg.range_resolution_m == pytest.approx(0.5450771964, rel=1e-9)
    assert cfg.n_range_bins == 512
    assert cfg.max_range_m == pytest.approx(279.0795245382, rel=1e-9)
    # v_max = lambda / (4 * 54 us) = 18.025 m/s; dv = lambda / (2 * 128 * 54 us) = 0.28164 m/s
    assert cfg.max_velocity_mps == pytest.approx(18.0250395623, rel=1e-9)
    assert cfg.velocity_resolution_mps == pytest.approx(0.2816412432, rel=1e-9)
    assert cfg.iq is False
    assert cfg.n_virtual == 1


def test_openradar_derived_by_hand():
    cfg = preset("openradar")
    # B_s = 60 MHz/us * 128 / 2.5 Msps = 60e12 * 51.2e-6 = 3.072 GHz -> dR = 4.879 cm
    assert cfg.sampled_bandwidth_hz == pytest.approx(3.072e9, rel=1e-12)
    assert cfg.range_resolution_m == pytest.approx(0.0487943454, rel=1e-9)
    assert cfg.max_range_m == pytest.approx(6.2456762083, rel=1e-9)
    # T_c = 30 us idle + 62 us ramp end = 92 us; lambda = c / 77.42 GHz
    assert cfg.chirp_period_s == pytest.approx(92e-6)
    assert cfg.max_velocity_mps == pytest.approx(5.2612594838, rel=1e-9)
    assert cfg.velocity_resolution_mps == pytest.approx(0.1644143589, rel=1e-9)


def test_virtual_positions_are_tx_major():
    cfg = preset("carrada")
    np.testing.assert_allclose(cfg.virtual_positions_lambda, np.arange(8) * 0.5)
    cfg = RadarConfig(**_base(tx_positions_lambda=(0.0, 10.0), rx_positions_lambda=(0.0, 1.0)))
    np.testing.assert_allclose(cfg.virtual_positions_lambda, [0.0, 1.0, 10.0, 11.0])


def test_axes():
    cfg = preset("carrada")
    r = cfg.range_axis_m()
    v = cfg.velocity_axis_mps()
    assert r.shape == (256,) and r[0] == 0.0
    assert r[1] == pytest.approx(cfg.range_resolution_m)
    assert v.shape == (64,) and v[32] == 0.0
    assert v[0] == pytest.approx(-cfg.max_velocity_mps)
    assert v[-1] == pytest.approx(cfg.max_velocity_mps - cfg.velocity_resolution_mps)


def test_presets_table_and_unknown_name():
    assert sorted(PRESETS) == ["carrada", "chirpseq", "mimo77", "openradar", "seed003"]
    for name in PRESETS:
        assert preset(name).name == name
    with pytest.raises(RadarConfigError, match="unknown radar preset 'ti'.*carrada.*seed003"):
        preset("ti")


@pytest.mark.parametrize(
    ("override", "pattern"),
    [
        ({"fs_hz": -1.0}, r"field 'fs_hz' = -1\.0: Input should be greater than 0"),
        ({"n_samples": 1}, r"field 'n_samples' = 1: .*greater than or equal to 2"),
        ({"carrier_hz": float("nan")}, r"field 'carrier_hz'"),
        ({"adc_bits": 40}, r"field 'adc_bits' = 40: .*less than or equal to 24"),
        ({"tx_positions_lambda": ()}, r"field 'tx_positions_lambda'"),
        ({"bogus_hz": 1.0}, r"field 'bogus_hz'.*Extra inputs"),
        ({"idle_s": 40e-6}, r"idle_s = 4e-05 s leaves no ramp"),
        # 256 / 10 Msps = 25.6 us + 20 us start > 40 us ramp
        ({"adc_start_s": 20e-6}, r"ends at adc_start_s \+ n_samples/fs_hz = 45\.6 us.*40 us"),
        # 64 chirps * 40 us = 2.56 ms > 1 / 500 Hz = 2 ms
        ({"frame_rate_hz": 500.0}, r"take n_tx\*n_chirps\*chirp_period_s = 2\.56 ms.*2 ms"),
    ],
)
def test_bad_parameters_raise_radar_config_error(override, pattern):
    with pytest.raises(RadarConfigError, match=pattern):
        RadarConfig(**_base(**override))


def test_frozen():
    cfg = preset("carrada")
    with pytest.raises(Exception, match="frozen"):
        cfg.fs_hz = 1.0  # type: ignore[misc]


def test_window_exactly_filling_the_ramp_is_allowed():
    # seed003 samples the whole 54 us ramp: 1024 / (1024 / 54 us) == 54 us up to rounding
    cfg = RadarConfig(**_base(n_samples=1024, fs_hz=1024 / 54e-6, chirp_period_s=54e-6))
    assert cfg.n_samples / cfg.fs_hz == pytest.approx(cfg.ramp_s)


@given(
    slope=st.floats(1e12, 1e14),
    fs=st.floats(1e6, 5e7),
    n_samples=st.integers(2, 2048),
    n_chirps=st.integers(1, 512),
    n_tx=st.integers(1, 4),
    iq=st.booleans(),
    carrier=st.floats(2e10, 1.5e11),
)
def test_derived_identities(slope, fs, n_samples, n_chirps, n_tx, iq, carrier):
    period = 1.01 * n_samples / fs
    cfg = RadarConfig(carrier_hz=carrier, slope_hz_per_s=slope, fs_hz=fs, n_samples=n_samples,
                      n_chirps=n_chirps, chirp_period_s=period, iq=iq,
                      tx_positions_lambda=tuple(float(i) for i in range(n_tx)),
                      frame_rate_hz=1.0 / (n_tx * n_chirps * period * 1.01))
    # dR = c fs / (2 S N); range axis = n_range_bins * dR = fs c / (2 S) (IQ) or half (real)
    assert math.isclose(cfg.range_resolution_m, C * fs / (2 * slope * n_samples), rel_tol=1e-12)
    full = fs * SPEED_OF_LIGHT_MPS / (2 * slope)
    expected = full if iq else full * (n_samples // 2) / n_samples
    assert math.isclose(cfg.max_range_m, expected, rel_tol=1e-12)
    # v_max is half the Doppler axis: M/2 bins of dv
    assert math.isclose(cfg.max_velocity_mps, n_chirps / 2 * cfg.velocity_resolution_mps,
                        rel_tol=1e-12)
    assert cfg.n_virtual == n_tx and len(cfg.range_axis_m()) == cfg.n_range_bins
