"""Seeded FMCW scene simulator: point targets to a raw ADC cube ``[virtual rx, chirp, sample]``.

Signal model: one point return of complex amplitude ``a`` at range ``R(t) = R0 + v t`` gives

    x[q, m, n] = a exp(2 pi j [(2 S / c) R(t) t_n + (2 f_c / c) R(t) + (p_tx + p_rx) sin(theta)])

with fast time ``t_n = adc_start_s + n / fs_hz`` (from ramp start), absolute time
``t = (m n_tx + s) T_c + t_n`` for chirp ``m`` of Tx slot ``s`` (so range-Doppler coupling
and the TDM-MIMO phase between slots are real), virtual channel ``q = s n_rx + r`` and
positions in wavelengths. Targets follow the radar equation ``|a| = FS 10^(gain_dbfs/20)
sqrt(sigma) / R0^2``; leakage and clutter have their amplitudes given in dBFS. Real
sampling keeps ``Re x``. Thermal noise is Gaussian with ``noise_dbfs`` rms per rail; the
ADC rounds to integer codes and clips at ``[-FS, FS - 1]``, ``FS = 2**(adc_bits - 1)``.

Conventions: ``velocity_mps > 0`` means receding (range grows); ``azimuth_deg > 0`` means
the phase grows along increasing element position. Doppler bins are in the fftshifted
layout (zero velocity at ``n_chirps // 2``), angle bins too (broadside at
``n_angle_bins // 2``).

The records (:class:`Target`, :class:`Scene`, :class:`Frame`, …) are defined in
:mod:`radar.scene_model` and the preset scenes in :mod:`radar.scene_presets`; this module
re-exports them, so ``radar.scene`` names every one.
"""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError
from radar.config import SPEED_OF_LIGHT_MPS, RadarConfig
from radar.scene_model import (
    Clutter,
    Frame,
    Leakage,
    Scene,
    Target,
    TargetTruth,
    target_amplitude_dbfs,
)
from radar.scene_presets import SCENE_PRESETS, carrada_scene, seed003_scene

__all__ = [
    "SCENE_PRESETS",
    "Clutter",
    "Frame",
    "Leakage",
    "Scene",
    "Target",
    "TargetTruth",
    "carrada_scene",
    "chirp_range_bins",
    "seed003_scene",
    "simulate_frame",
    "simulate_frames",
    "target_amplitude_dbfs",
]


def _returns(config: RadarConfig, scene: Scene, rng: np.random.Generator) -> tuple:
    """All point returns as arrays ``(range0_m, velocity_mps, sin_az, amplitude_codes)``.

    Draws from ``rng`` the clutter, then the leakage's chirp phase noise (see
    :func:`_jitter`), in that order.
    """
    fs = float(config.full_scale_code)
    t = scene.targets
    r0 = [x.range_m for x in t] + [x.range_m for x in scene.leakage]
    vel = [x.velocity_mps for x in t] + [0.0] * len(scene.leakage)
    az = [x.azimuth_deg for x in t] + [0.0] * len(scene.leakage)
    amp = [fs * 10 ** (target_amplitude_dbfs(x.rcs_dbsm, x.range_m, scene.gain_dbfs) / 20)
           for x in t]
    amp += [fs * 10 ** (x.amplitude_dbfs / 20) * np.exp(1j * np.deg2rad(x.phase_deg))
            for x in scene.leakage]
    arrays = [np.asarray(a, dtype=d) for a, d in
              ((r0, float), (vel, float), (np.sin(np.deg2rad(az)), float), (amp, complex))]
    if scene.clutter is not None:
        cl = scene.clutter
        k = cl.n_scatterers
        c_r = rng.uniform(cl.min_range_m, cl.max_range_m, k)
        c_az = rng.uniform(-cl.max_azimuth_deg, cl.max_azimuth_deg, k)
        c_amp = fs * 10 ** (cl.amplitude_dbfs / 20) * (
            rng.standard_normal(k) + 1j * rng.standard_normal(k)) / np.sqrt(2)
        extra = (c_r, np.zeros(k), np.sin(np.deg2rad(c_az)), c_amp)
        arrays = [np.concatenate([a, e]) for a, e in zip(arrays, extra, strict=True)]
    return (*arrays, _jitter(config, scene, rng))


def _jitter(config: RadarConfig, scene: Scene, rng: np.random.Generator) -> dict:
    """Return index -> per-chirp phase factor ``exp(j phi)``, shape [n_virtual, M, 1].

    One Gaussian phase of rms ``phase_noise_deg`` per transmitted chirp (chirp ``m`` of
    Tx slot ``s`` is the ``m n_tx + s``-th), shared by the receivers of that chirp. Only
    leakage with ``phase_noise_deg > 0`` draws, so other scenes use no random numbers here.
    """
    out = {}
    slot = np.repeat(np.arange(config.n_tx), config.n_rx)
    for i, lk in enumerate(scene.leakage):
        if lk.phase_noise_deg > 0:
            phi = np.deg2rad(lk.phase_noise_deg) * rng.standard_normal(
                (config.n_chirps, config.n_tx))
            out[len(scene.targets) + i] = np.exp(1j * phi[:, slot].T)[:, :, None]
    return out


def _check_ranges(config: RadarConfig, scene: Scene) -> None:
    """Every return must stay on the range axis (0, max_range_m] for the whole frame."""
    limit = config.max_range_m
    for i, tg in enumerate(scene.targets):
        end = tg.range_m + tg.velocity_mps * config.frame_time_s
        worst = max(tg.range_m, end)
        if worst > limit or end <= 0:
            raise RadarConfigError(
                f"Scene '{scene.name}' target {i} ('{tg.name}'): range goes from "
                f"{tg.range_m:g} m to {end:g} m during the frame, outside (0, {limit:.4g}] m, "
                f"the max_range_m of config '{config.name}'; move the target or pick a "
                "longer-range config", node=tg.name or None)
    far = [x.range_m for x in scene.leakage]
    if scene.clutter is not None:
        far.append(scene.clutter.max_range_m)
    if far and max(far) > limit:
        raise RadarConfigError(
            f"Scene '{scene.name}': leakage/clutter range {max(far):g} m exceeds "
            f"max_range_m = {limit:.4g} m of config '{config.name}'")


def _beat_cube(config: RadarConfig, returns: tuple) -> np.ndarray:
    """Noise-free complex beat signal summed over returns, shape [n_virtual, M, N]."""
    r0, vel, sin_az, amp, jitter = returns
    c = SPEED_OF_LIGHT_MPS
    t_fast = config.adc_start_s + np.arange(config.n_samples) / config.fs_hz
    slot = np.repeat(np.arange(config.n_tx), config.n_rx)
    t_chirp = (np.arange(config.n_chirps)[None, :] * config.n_tx + slot[:, None]) \
        * config.chirp_period_s
    t_abs = t_chirp[:, :, None] + t_fast[None, None, :]
    cycles_per_m = (2 * config.slope_hz_per_s / c) * t_fast + 2 * config.carrier_hz / c
    pos = config.virtual_positions_lambda[:, None, None]
    cube = np.zeros(t_abs.shape, dtype=np.complex128)
    for k in range(r0.size):  # a handful of returns; each is vectorized over the cube
        cycles = (r0[k] + vel[k] * t_abs) * cycles_per_m + pos * sin_az[k]
        a = amp[k] * jitter[k] if k in jitter else amp[k]
        cube += a * np.exp(2j * np.pi * (cycles - np.floor(cycles)))
    return cube


def _truth(config: RadarConfig, scene: Scene, n_angle_bins: int) -> tuple[TargetTruth, ...]:
    """Expected bins of each target (see :class:`TargetTruth`)."""
    c, n, m = SPEED_OF_LIGHT_MPS, config.n_samples, config.n_chirps
    t_fast_mid = config.adc_start_s + (n - 1) / (2 * config.fs_hz)
    t_frame_mid = (m * config.n_tx - 1) / 2 * config.chirp_period_s
    pos = config.virtual_positions_lambda
    step = np.diff(pos)
    uniform = pos.size > 1 and step[0] != 0 and np.allclose(step, step[0], atol=1e-9)
    out = []
    for tg in scene.targets:
        v = tg.velocity_mps
        beat_hz = (2 * config.slope_hz_per_s / c) * (
            tg.range_m + v * (t_frame_mid + 2 * t_fast_mid)) + 2 * config.carrier_hz * v / c
        r_exact = beat_hz * n / config.fs_hz
        r_exact = r_exact % n if config.iq else abs(r_exact)
        f_doppler = 2 * v * (config.carrier_hz + config.slope_hz_per_s * t_fast_mid) / c
        d_exact = (m // 2 + f_doppler * config.n_tx * config.chirp_period_s * m) % m
        angle = None
        if uniform:
            shift = round(n_angle_bins * step[0] * np.sin(np.deg2rad(tg.azimuth_deg)))
            angle = int((shift + n_angle_bins // 2) % n_angle_bins)
        out.append(TargetTruth(
            name=tg.name, range_m=tg.range_m, velocity_mps=v, azimuth_deg=tg.azimuth_deg,
            rcs_dbsm=tg.rcs_dbsm,
            amplitude_dbfs=target_amplitude_dbfs(tg.rcs_dbsm, tg.range_m, scene.gain_dbfs),
            range_bin=int(round(r_exact)) % n if config.iq else int(round(r_exact)),
            range_bin_exact=float(r_exact), doppler_bin=int(round(d_exact)) % m,
            doppler_bin_exact=float(d_exact),
            aliased=not (-config.max_velocity_mps <= v < config.max_velocity_mps),
            angle_bin=angle))
    return tuple(out)


def chirp_range_bins(config: RadarConfig, truth: TargetTruth) -> np.ndarray:
    """The exact range bin of a target on each chirp of Tx slot 0 (range migration).

    ``f_b(m) N / fs`` with the beat frequency at mid-window of chirp ``m``,
    ``f_b(m) = (2S/c)(R0 + v (m n_tx T_c + 2 t_fast_mid)) + 2 f_c v / c``: the frame-level
    ``TargetTruth.range_bin_exact`` is this at mid-frame.

    Parameters
    ----------
    config : RadarConfig
        The sensor the frame was simulated with.
    truth : TargetTruth
        One target's truth (its ``range_m`` and ``velocity_mps`` are used).

    Returns
    -------
    numpy.ndarray
        float64, shape (n_chirps,); wrapped into ``[0, N)`` for IQ, folded (``abs``) for
        real sampling, like ``range_bin_exact``.

    Examples
    --------
    A target closing at 30 m/s on the ``carrada`` sensor moves 0.136 m (0.68 bins) in a frame:

    >>> from radar.config import preset
    >>> cfg = preset("carrada")
    >>> frame = simulate_frame(cfg, Scene(targets=(Target(range_m=20.0, velocity_mps=-30.0),),
    ...                                   noise_dbfs=None), seed=0)
    >>> bins = chirp_range_bins(cfg, frame.truth[0])
    >>> round(float(bins[0] - bins[-1]), 2)
    0.68
    """
    c, n = SPEED_OF_LIGHT_MPS, config.n_samples
    t_fast_mid = config.adc_start_s + (n - 1) / (2 * config.fs_hz)
    t_chirp = np.arange(config.n_chirps) * config.n_tx * config.chirp_period_s
    v = truth.velocity_mps
    beat_hz = (2 * config.slope_hz_per_s / c) * (
        truth.range_m + v * (t_chirp + 2 * t_fast_mid)) + 2 * config.carrier_hz * v / c
    exact = beat_hz * n / config.fs_hz
    return exact % n if config.iq else np.abs(exact)


def _adc(x: np.ndarray, full_scale: int) -> tuple[np.ndarray, int]:
    """Round one rail to integer codes and clip to [-FS, FS - 1]; also count the clips."""
    codes = np.rint(x)
    n_clipped = int(np.count_nonzero((codes < -full_scale) | (codes > full_scale - 1)))
    return np.clip(codes, -full_scale, full_scale - 1), n_clipped


def simulate_frame(config: RadarConfig, scene: Scene, *, seed: int,
                   n_angle_bins: int = 64) -> Frame:
    """Simulate one frame of raw ADC data, with per-target ground truth.

    Parameters
    ----------
    config : RadarConfig
        The sensor.
    scene : Scene
        Targets, leakage, clutter, noise and ADC switches.
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same cube.
    n_angle_bins : int
        Angle-FFT length the truth's ``angle_bin`` refers to.

    Returns
    -------
    Frame
        ``adc`` shaped ``[n_virtual, n_chirps, n_samples]`` (virtual index
        ``tx * n_rx + rx``), complex128 (IQ) or float64 (real), in ADC codes.

    Raises
    ------
    RadarConfigError
        A return leaves the range axis during the frame, ``seed`` is negative or not an
        integer, or ``n_angle_bins < 1``.

    Notes
    -----
    See the module docstring for the signal model. Truth bins: range
    ``f_b N / fs`` with ``f_b = (2S/c) R_mid + 2 v f_c / c``; Doppler
    ``M//2 + 2 v f_ctr n_tx T_c M / c`` wrapped into ``[0, M)``, ``f_ctr`` the carrier at
    the middle of the sample window; angle ``n_angle_bins//2 + round(K d sin(theta))``.
    A moving target's Tx slots differ by the Doppler phase ``2 v f_ctr T_c / c`` cycles;
    compensate it with the Doppler bin before the angle FFT (ambiguous when aliased).

    Examples
    --------
    >>> from radar.config import preset
    >>> frame = simulate_frame(preset("carrada"), carrada_scene(), seed=0)
    >>> frame.adc.shape, frame.adc.dtype
    ((8, 64, 256), dtype('complex128'))
    >>> [(t.range_bin, t.doppler_bin, t.aliased) for t in frame.truth][-1]
    (200, 48, True)
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise RadarConfigError(f"simulate_frame: seed must be a non-negative int, got {seed!r}")
    if n_angle_bins < 1:
        raise RadarConfigError(f"simulate_frame: n_angle_bins must be >= 1, got {n_angle_bins}")
    _check_ranges(config, scene)
    rng = np.random.default_rng(seed)
    signal = _beat_cube(config, _returns(config, scene, rng))
    fs_code = config.full_scale_code
    rails = [signal.real, signal.imag] if config.iq else [signal.real]
    if scene.noise_dbfs is not None:
        sigma = fs_code * 10 ** (scene.noise_dbfs / 20)
        rails = [r + sigma * rng.standard_normal(r.shape) for r in rails]
    n_clipped = 0
    if scene.quantize:
        quantized = [_adc(r, fs_code) for r in rails]
        rails = [q for q, _ in quantized]
        n_clipped = sum(k for _, k in quantized)
    adc = rails[0] + 1j * rails[1] if config.iq else rails[0]
    adc.flags.writeable = False
    return Frame(adc=adc, truth=_truth(config, scene, n_angle_bins), config=config,
                 scene=scene, seed=int(seed), n_angle_bins=n_angle_bins, n_clipped=n_clipped)


def simulate_frames(config: RadarConfig, scene: Scene, seeds) -> np.ndarray:
    """The ADC cubes of one frame per seed, on a leading frames axis (a calibration set).

    Parameters
    ----------
    config : RadarConfig
    scene : Scene
    seeds : iterable of int
        One frame per seed (:func:`simulate_frame`).

    Returns
    -------
    ndarray, shape ``(len(seeds), n_virtual, n_chirps, n_samples)``

    Examples
    --------
    >>> from radar.config import preset
    >>> from radar.scene_presets import carrada_scene
    >>> simulate_frames(preset("carrada"), carrada_scene(), seeds=(1, 2)).shape
    (2, 8, 64, 256)
    """
    cubes = [simulate_frame(config, scene, seed=int(s)).adc for s in seeds]
    if not cubes:
        raise RadarConfigError("simulate_frames needs at least one seed")
    return np.stack(cubes)
