r"""Range-Doppler power maps of point scatterers, synthesised without an ADC cube.

The conventional chain's noise-free maths for point targets, evaluated per point instead
of per ADC sample: a point at fractional range bin :math:`\rho` and Doppler bin
:math:`\delta` (:func:`point_bins`, the formulas of :func:`radar.scene.simulate_frame`'s
truth) with amplitude :math:`a` (radar equation, in ADC codes), carrier phase
:math:`4\pi R/\lambda` and virtual-element phase :math:`2\pi p_q \sin\theta` gives

.. math::

    X_q[d, r] = \sum_k a_k e^{j\varphi_{qk}} \, K_M(\delta_k - d)\, K_N(\rho_k - r), \qquad
    K_L(x)[b] = \sum_{l<L} w_l e^{2\pi j l x/L}

(Hann windows, the Doppler bins fftshifted), plus complex Gaussian noise of variance
:math:`2\sigma^2 \sum w_N^2 \sum w_M^2` per cell, and :math:`P = \sum_q |X_q|^2` — the
chain ``window → DFT → window → DFT → |.|² → Σrx`` (:func:`synthesize_rd`).  Left out:
range migration and the TDM slot phase within a frame, ADC rounding and clipping,
near-range leakage (``radar.scene`` has them; a test checks both agree on a point
target).  :func:`noise_floor` is the analytic median of a noise-only cell and
:func:`db_above_noise` refers a map to its own median.

Used by :mod:`radar.roi_dataset`, which re-exports every name here.
"""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError
from radar.config import SPEED_OF_LIGHT_MPS, RadarConfig
from radar.signatures import Scatterers
from radar.windows import window_coefficients

__all__ = ["db_above_noise", "noise_floor", "point_bins", "synthesize_rd"]


def point_bins(config: RadarConfig, range_m: np.ndarray,
               velocity_mps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fractional range and (fftshifted) Doppler bins of points, as ``simulate_frame``'s truth.

    Examples
    --------
    >>> from radar.config import preset
    >>> cfg = preset("carrada")
    >>> r, d = point_bins(cfg, np.array([10.0]), np.array([0.0]))
    >>> round(float(r[0]), 3), float(d[0])
    (50.04, 32.0)
    """
    c, n, m = SPEED_OF_LIGHT_MPS, config.n_samples, config.n_chirps
    t_fast_mid = config.adc_start_s + (n - 1) / (2 * config.fs_hz)
    t_frame_mid = (m * config.n_tx - 1) / 2 * config.chirp_period_s
    v = np.asarray(velocity_mps, dtype=np.float64)
    beat_hz = (2 * config.slope_hz_per_s / c) * (
        np.asarray(range_m, dtype=np.float64) + v * (t_frame_mid + 2 * t_fast_mid)
    ) + 2 * config.carrier_hz * v / c
    r_exact = beat_hz * n / config.fs_hz
    r_exact = r_exact % n if config.iq else np.abs(r_exact)
    f_doppler = 2 * v * (config.carrier_hz + config.slope_hz_per_s * t_fast_mid) / c
    d_exact = (m // 2 + f_doppler * config.n_tx * config.chirp_period_s * m) % m
    return r_exact, d_exact


#: Cosine-sum windows ``w_l = sum_i a_i cos(2 pi i l / (L - 1))`` (symmetric, as radar.windows).
_COSINE_TERMS: dict[str, tuple[float, ...]] = {
    "rect": (1.0,), "hann": (0.5, -0.5), "hamming": (0.54, -0.46), "blackman": (0.42, -0.5, 0.08),
}


def _dirichlet(theta: np.ndarray, length: int) -> np.ndarray:
    """:math:`D(\\theta) = \\sum_{l<L} e^{j\\theta l} = (e^{j\\theta L} - 1)/(e^{j\\theta} - 1)`."""
    den = np.expm1(1j * theta)
    small = np.abs(den) < 1e-9
    return np.where(small, length, np.expm1(1j * theta * length) / np.where(small, 1.0, den))


def _kernels(frac_bins: np.ndarray, window: str, length: int, bins: np.ndarray) -> np.ndarray:
    """``(K, B)`` window responses :math:`K_L(x_k - b) = \\sum_l w_l e^{2\\pi j l (x_k - b)/L}`.

    Closed form for the cosine-sum windows: each term :math:`a_i \\cos(\\phi_i l)` adds
    :math:`\\tfrac{a_i}{2}[D(\\theta + \\phi_i) + D(\\theta - \\phi_i)]`, :math:`\\theta =
    2\\pi(x - b)/L`, :math:`\\phi_i = 2\\pi i/(L - 1)`.
    """
    theta = 2 * np.pi * np.subtract.outer(frac_bins, bins) / length
    terms = _COSINE_TERMS[window]
    if length == 1:
        return np.ones(theta.shape, dtype=np.complex128)
    out = terms[0] * _dirichlet(theta, length)
    for i, a in enumerate(terms[1:], start=1):
        phi = 2 * np.pi * i / (length - 1)
        out = out + a / 2 * (_dirichlet(theta + phi, length) + _dirichlet(theta - phi, length))
    return out


def noise_floor(config: RadarConfig, noise_dbfs: float, window: str = "hann") -> float:
    """The median power of a noise-only cell of :func:`synthesize_rd`'s map.

    Each virtual channel's cell is complex Gaussian with variance :math:`2\\sigma^2` (with
    :math:`\\sigma` = rms per rail x window gains), so the sum over :math:`Q` channels is
    :math:`\\sigma^2 \\chi^2_{2Q}`; its median is :math:`\\sigma^2 \\cdot
    \\mathrm{median}(\\chi^2_{2Q})`.

    Examples
    --------
    >>> from radar.config import preset
    >>> cfg = preset("carrada")
    >>> rd = synthesize_rd(cfg, Scatterers(*(np.ones(0) for _ in range(4))),
    ...                    np.random.default_rng(0), noise_dbfs=-70.0)
    >>> bool(abs(10 * np.log10(np.median(rd) / noise_floor(cfg, -70.0))) < 0.1)
    True
    """
    from scipy.stats import chi2

    w_r = window_coefficients(window, config.n_samples)
    w_d = window_coefficients(window, config.n_chirps)
    sigma2 = (config.full_scale_code * 10 ** (noise_dbfs / 20)) ** 2 * np.sum(w_r ** 2) \
        * np.sum(w_d ** 2)
    return float(sigma2 * chi2.median(2 * config.n_virtual))


def synthesize_rd(config: RadarConfig, points: Scatterers, rng: np.random.Generator, *,
                  noise_dbfs: float = -70.0, gain_dbfs: float = -20.0,
                  window: str = "hann", range_bins: np.ndarray | None = None,
                  doppler_bins: np.ndarray | None = None) -> np.ndarray:
    """The range-Doppler power map ``[doppler, range]`` of point scatterers plus noise.

    Parameters
    ----------
    config : RadarConfig
        The sensor (IQ sampling: all range bins are kept).
    points : Scatterers
        The points of the frame (ranges must be positive).
    rng : numpy.random.Generator
        Source of the noise.
    noise_dbfs : float
        Thermal noise rms per rail, dBFS.
    gain_dbfs : float
        Amplitude of a 0 dBsm point at 1 m, dBFS (:func:`radar.scene.target_amplitude_dbfs`).
    window : str
        Window of both DFTs.
    range_bins, doppler_bins : ndarray of int, optional
        Compute only these bins (a sub-grid, e.g. an ROI; Doppler bins fftshifted);
        default: the whole map.

    Returns
    -------
    ndarray of float64, shape (doppler bins, range bins)
        :math:`\\sum_q |X_q|^2` (see the module docstring), Doppler bins fftshifted.

    Raises
    ------
    RadarConfigError
        For a real-sampling config (only IQ is synthesised).

    Examples
    --------
    A noise-free point at 10 m, still: the peak sits in range bin 50, Doppler bin 32.

    >>> from radar.config import preset
    >>> cfg = preset("carrada")
    >>> pts = Scatterers(np.array([10.0]), np.array([0.0]), np.array([0.0]), np.array([0.0]))
    >>> rd = synthesize_rd(cfg, pts, np.random.default_rng(0), noise_dbfs=-300.0)
    >>> np.unravel_index(rd.argmax(), rd.shape)
    (np.int64(32), np.int64(50))
    """
    if not config.iq:
        raise RadarConfigError(f"synthesize_rd: config {config.name!r} samples real values; "
                               "only IQ configs are synthesised (use radar.scene.simulate_frame)")
    fs = float(config.full_scale_code)
    w_r = window_coefficients(window, config.n_samples)
    w_d = window_coefficients(window, config.n_chirps)
    r_out = np.arange(config.n_samples) if range_bins is None else np.asarray(range_bins)
    d_out = np.arange(config.n_chirps) if doppler_bins is None else np.asarray(doppler_bins)
    r_bin, d_bin = point_bins(config, points.range_m, points.velocity_mps)
    amp = fs * 10 ** (gain_dbfs / 20) * 10 ** (points.rcs_dbsm / 20) / points.range_m ** 2
    carrier = np.exp(4j * np.pi * points.range_m / config.wavelength_m)
    steer = np.exp(2j * np.pi * np.outer(config.virtual_positions_lambda,
                                         np.sin(np.deg2rad(points.azimuth_deg))))
    coef = steer * (amp * carrier)  # (q, k)
    k_r = _kernels(r_bin, window, config.n_samples, r_out)  # (k, range)
    k_d = _kernels(d_bin, window, config.n_chirps, d_out)  # (k, doppler)
    cube = (coef[:, None, :] * k_d.T[None]) @ k_r  # (q, doppler, range)
    sigma = fs * 10 ** (noise_dbfs / 20) * np.sqrt(np.sum(w_r ** 2) * np.sum(w_d ** 2))
    noise = rng.standard_normal((2, *cube.shape))
    cube += sigma * (noise[0] + 1j * noise[1])
    return np.sum(cube.real ** 2 + cube.imag ** 2, axis=0)


def db_above_noise(power: np.ndarray, axes: tuple[int, ...] = (-2, -1)) -> np.ndarray:
    """``10 log10(P / median(P))`` per map: dB above the noise floor (the map's median).

    Examples
    --------
    >>> db_above_noise(np.array([[1.0, 1.0, 100.0]])).tolist()
    [[0.0, 0.0, 20.0]]
    """
    p = np.asarray(power, dtype=np.float64)
    floor = np.median(p, axis=axes, keepdims=True)
    return 10 * np.log10(np.maximum(p, 1e-300) / np.maximum(floor, 1e-300))
