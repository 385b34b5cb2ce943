"""FMCW radar configuration: the sensor's parameters, its derived resolutions, and presets.

A :class:`RadarConfig` describes one FMCW sensor and one frame of TDM-MIMO chirps. Every
field carries its unit in its name; every derived quantity is a property whose docstring
gives its formula. Resolutions follow from the *sampled* bandwidth, the part of the sweep
the ADC actually sees: ``B_s = slope_hz_per_s * n_samples / fs_hz``.

Examples
--------
>>> from radar.config import preset
>>> cfg = preset("seed003")
>>> cfg.n_samples, cfg.n_chirps, cfg.n_range_bins
(1024, 128, 512)
>>> round(cfg.range_resolution_m, 4), round(cfg.max_range_m, 1)
(0.5451, 279.1)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ir.errors import RadarConfigError

__all__ = [
    "SPEED_OF_LIGHT_MPS",
    "PRESETS",
    "RadarConfig",
    "RadarModel",
    "carrada",
    "openradar",
    "preset",
    "seed003",
]

SPEED_OF_LIGHT_MPS = 299_792_458.0
"""Speed of light in vacuum, m/s (exact, SI)."""

_REL_TOL = 1e-9  # slack for timing comparisons that are exact on paper


def _describe(model: str, err: ValidationError) -> str:
    """One sentence per pydantic error: field path, offending value, and the rule broken."""
    parts = []
    for item in err.errors(include_url=False):
        field = ".".join(str(p) for p in item["loc"]) or "<model>"
        parts.append(f"field '{field}' = {item.get('input')!r}: {item['msg']}")
    return f"{model}: " + "; ".join(parts)


class RadarModel(BaseModel):
    """Base of radarsnn's radar records: frozen, no extra fields, no NaN/inf.

    Construction errors are raised as :class:`ir.errors.RadarConfigError` naming the
    field, the value given and the rule (limit) it breaks.

    Examples
    --------
    >>> from ir.errors import RadarConfigError
    >>> try:
    ...     RadarConfig(carrier_hz=77e9, slope_hz_per_s=1e13, fs_hz=-1.0, n_samples=8,
    ...                 n_chirps=4, chirp_period_s=1e-5)
    ... except RadarConfigError as err:
    ...     print(err)
    RadarConfig: field 'fs_hz' = -1.0: Input should be greater than 0
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as err:
            raise RadarConfigError(_describe(type(self).__name__, err)) from err


class RadarConfig(RadarModel):
    """One FMCW sensor and its frame of TDM-MIMO chirps.

    Parameters
    ----------
    carrier_hz : float
        Start frequency of the ramp, Hz. The beat-phase model uses it as ``f_c``.
    slope_hz_per_s : float
        Ramp slope ``S``, Hz/s.
    fs_hz : float
        ADC sample rate, Hz (complex samples per second for IQ, real ones otherwise).
    n_samples : int
        ADC samples per chirp ``N``.
    n_chirps : int
        Chirps per Tx per frame ``M`` (the Doppler FFT length).
    chirp_period_s : float
        Time between consecutive chirp starts ``T_c`` (ramp plus idle), s.
    idle_s : float
        Idle time inside each period, s; the ramp lasts ``chirp_period_s - idle_s``.
    adc_start_s : float
        Delay from ramp start to the first ADC sample, s.
    tx_positions_lambda, rx_positions_lambda : tuple of float
        Element x-positions in wavelengths. Tx slots fire in turn (TDM-MIMO).
    adc_bits : int
        ADC resolution; full scale is ``2**(adc_bits - 1)`` codes per rail.
    iq : bool
        True for complex (IQ) sampling, False for real sampling.
    frame_rate_hz : float
        Frames per second; the chirps of a frame must fit in ``1/frame_rate_hz``.
    name : str
        A label, e.g. the preset's name.

    Raises
    ------
    RadarConfigError
        A field is out of range, or the sample window does not fit in the ramp, or the
        frame's chirps do not fit in the frame period.

    Examples
    --------
    >>> cfg = RadarConfig(carrier_hz=77e9, slope_hz_per_s=30e12, fs_hz=10e6, n_samples=256,
    ...                   n_chirps=64, chirp_period_s=40e-6, tx_positions_lambda=(0.0, 2.0),
    ...                   rx_positions_lambda=(0.0, 0.5, 1.0, 1.5))
    >>> cfg.n_virtual, cfg.n_range_bins
    (8, 256)
    >>> round(cfg.sampled_bandwidth_hz / 1e6, 1)
    768.0
    """

    carrier_hz: float = Field(gt=0)
    slope_hz_per_s: float = Field(gt=0)
    fs_hz: float = Field(gt=0)
    n_samples: int = Field(ge=2, le=1 << 16)
    n_chirps: int = Field(ge=1, le=1 << 16)
    chirp_period_s: float = Field(gt=0)
    idle_s: float = Field(default=0.0, ge=0)
    adc_start_s: float = Field(default=0.0, ge=0)
    tx_positions_lambda: tuple[float, ...] = Field(default=(0.0,), min_length=1, max_length=64)
    rx_positions_lambda: tuple[float, ...] = Field(default=(0.0,), min_length=1, max_length=64)
    adc_bits: int = Field(default=16, ge=2, le=24)
    iq: bool = True
    frame_rate_hz: float = Field(default=10.0, gt=0)
    name: str = "custom"

    @model_validator(mode="after")
    def _check_timing(self) -> RadarConfig:
        ramp_s = self.chirp_period_s - self.idle_s
        if ramp_s <= 0:
            raise RadarConfigError(
                f"RadarConfig '{self.name}': idle_s = {self.idle_s:g} s leaves no ramp in "
                f"chirp_period_s = {self.chirp_period_s:g} s; make idle_s < chirp_period_s"
           )
        window_end_s = self.adc_start_s + self.n_samples / self.fs_hz
        if window_end_s > ramp_s * (1 + _REL_TOL):
            raise RadarConfigError(
                f"RadarConfig '{self.name}': the sample window ends at adc_start_s + "
                f"n_samples/fs_hz = {window_end_s * 1e6:.4g} us, after the ramp ends at "
                f"chirp_period_s - idle_s = {ramp_s * 1e6:.4g} us; raise fs_hz, lower "
                "n_samples or adc_start_s, or lengthen the chirp"
           )
        active_s = self.n_tx * self.n_chirps * self.chirp_period_s
        if active_s > (1 + _REL_TOL) / self.frame_rate_hz:
            raise RadarConfigError(
                f"RadarConfig '{self.name}': the frame's chirps take n_tx*n_chirps*"
                f"chirp_period_s = {active_s * 1e3:.4g} ms, longer than the frame period "
                f"1/frame_rate_hz = {1e3 / self.frame_rate_hz:.4g} ms; lower frame_rate_hz "
                "or n_chirps"
           )
        return self

    @property
    def n_tx(self) -> int:
        """Number of Tx elements (TDM slots per chirp loop)."""
        return len(self.tx_positions_lambda)

    @property
    def n_rx(self) -> int:
        """Number of Rx elements."""
        return len(self.rx_positions_lambda)

    @property
    def n_virtual(self) -> int:
        """Virtual channels ``n_tx * n_rx``, tx-major: index ``tx * n_rx + rx``."""
        return self.n_tx * self.n_rx

    @property
    def virtual_positions_lambda(self) -> np.ndarray:
        """Virtual element positions ``p_tx + p_rx`` (wavelengths), tx-major, shape (n_virtual,)."""
        tx = np.asarray(self.tx_positions_lambda, dtype=np.float64)
        rx = np.asarray(self.rx_positions_lambda, dtype=np.float64)
        return (tx[:, None] + rx[None, :]).ravel()

    @property
    def ramp_s(self) -> float:
        """Ramp duration ``chirp_period_s - idle_s``, s."""
        return self.chirp_period_s - self.idle_s

    @property
    def frame_time_s(self) -> float:
        """Active time of a frame ``n_tx * n_chirps * T_c``, s."""
        return self.n_tx * self.n_chirps * self.chirp_period_s

    @property
    def sampled_bandwidth_hz(self) -> float:
        """Sweep seen by the ADC ``B_s = S * N / fs``, Hz."""
        return self.slope_hz_per_s * self.n_samples / self.fs_hz

    @property
    def wavelength_m(self) -> float:
        """Carrier wavelength ``lambda = c / carrier_hz``, m."""
        return SPEED_OF_LIGHT_MPS / self.carrier_hz

    @property
    def range_resolution_m(self) -> float:
        """Range bin width ``dR = c / (2 B_s)``, m."""
        return SPEED_OF_LIGHT_MPS / (2.0 * self.sampled_bandwidth_hz)

    @property
    def n_range_bins(self) -> int:
        """Useful range bins: ``N`` for IQ sampling, ``N // 2`` (positive half) for real."""
        return self.n_samples if self.iq else self.n_samples // 2

    @property
    def max_range_m(self) -> float:
        """Range axis end ``n_range_bins * dR``: ``fs c / (2 S)`` for IQ, half that for real, m."""
        return self.n_range_bins * self.range_resolution_m

    @property
    def velocity_resolution_mps(self) -> float:
        """Doppler bin width ``dv = lambda / (2 n_tx M T_c)``, m/s."""
        return self.wavelength_m / (2.0 * self.n_tx * self.n_chirps * self.chirp_period_s)

    @property
    def max_velocity_mps(self) -> float:
        """Unambiguous speed ``v_max = lambda / (4 n_tx T_c)``, m/s; observed: [-v_max, v_max)."""
        return self.wavelength_m / (4.0 * self.n_tx * self.chirp_period_s)

    @property
    def full_scale_code(self) -> int:
        """ADC full scale per rail ``2**(adc_bits - 1)`` codes; codes span [-FS, FS - 1]."""
        return 1 << (self.adc_bits - 1)

    def range_axis_m(self) -> np.ndarray:
        """Range of each range bin ``k * dR`` for ``k = 0 .. n_range_bins - 1``, m.

        Returns
        -------
        numpy.ndarray
            float64, shape (n_range_bins,).

        Examples
        --------
        >>> preset("seed003").range_axis_m()[:3].round(3)
        array([0.   , 0.545, 1.09 ])
        """
        return np.arange(self.n_range_bins) * self.range_resolution_m

    def velocity_axis_mps(self) -> np.ndarray:
        """Velocity of each fftshifted Doppler bin ``(k - M//2) * dv``, m/s (zero at ``M//2``).

        Returns
        -------
        numpy.ndarray
            float64, shape (n_chirps,), from ``-v_max`` up to ``v_max - dv`` for even ``M``.

        Examples
        --------
        >>> axis = preset("carrada").velocity_axis_mps()
        >>> axis.shape, float(axis[32])
        ((64,), 0.0)
        """
        return (np.arange(self.n_chirps) - self.n_chirps // 2) * self.velocity_resolution_mps


def carrada() -> RadarConfig:
    """A CARRADA-like sensor: 77 GHz, 2 Tx x 4 Rx, 256 IQ samples x 64 chirps, 10 frames/s.

    Slope 29.3 MHz/us and 10 Msps give ``B_s = 750.08 MHz``, ``dR = 0.1998 m``, 51.2 m
    range; ``T_c = 36 us`` gives ``dv = 0.4225 m/s`` and ``v_max = 13.52 m/s``. The virtual
    array is a uniform 8-element line at lambda/2 (Tx at 0 and 2 lambda).

    Returns
    -------
    RadarConfig

    Examples
    --------
    >>> cfg = carrada()
    >>> round(cfg.range_resolution_m, 4), round(cfg.velocity_resolution_mps, 4)
    (0.1998, 0.4225)
    """
    return RadarConfig(
        name="carrada", carrier_hz=77e9, slope_hz_per_s=29.3e12, fs_hz=10e6, n_samples=256,
        n_chirps=64, chirp_period_s=36e-6, idle_s=6e-6, adc_start_s=4e-6,
        tx_positions_lambda=(0.0, 2.0), rx_positions_lambda=(0.0, 0.5, 1.0, 1.5),
        adc_bits=16, iq=True, frame_rate_hz=10.0,
   )


def seed003() -> RadarConfig:
    """López-Randulfe et al.'s (2021) sensor: 77 GHz, 1 Tx x 1 Rx, 1024 real samples x 128 chirps.

    The paper gives a 275 MHz sweep over a 54 us chirp; the ADC samples the whole ramp,
    so ``fs = 1024 / 54 us = 18.96 MHz`` and ``S = 275 MHz / 54 us``. Then
    ``dR = c / (2 * 275 MHz) = 0.5451 m``, 512 range bins reach 279.1 m. Chirps follow
    back to back (``T_c = 54 us``, no idle: not stated by the paper), so
    ``v_max = 18.03 m/s`` and ``dv = 0.2816 m/s``. 12-bit ADC and 20 frames/s are
    assumptions.

    Returns
    -------
    RadarConfig

    Examples
    --------
    >>> cfg = seed003()
    >>> round(cfg.sampled_bandwidth_hz / 1e6, 3), round(cfg.max_velocity_mps, 2)
    (275.0, 18.03)
    """
    return RadarConfig(
        name="seed003", carrier_hz=77e9, slope_hz_per_s=275e6 / 54e-6, fs_hz=1024 / 54e-6,
        n_samples=1024, n_chirps=128, chirp_period_s=54e-6, idle_s=0.0, adc_start_s=0.0,
        adc_bits=12, iq=False, frame_rate_hz=20.0,
   )


def openradar() -> RadarConfig:
    """The OpenRadar capture's sensor (``radar/data/openradar``): a TI IWR, IQ sampling.

    From the source notebook: 77.42 GHz start, 60 MHz/us, 2.5 Msps, 128 samples, idle
    30 us, ramp end 62 us (so ``T_c = 92 us``), 2 Tx. Assumed here (not stated): 4 Rx at
    lambda/2 with Tx at 0 and 2 lambda, the capture's 128 chirps as 64 loops of the two Tx
    slots, ``adc_start_s = 6 us``, 16-bit ADC, 10 frames/s. ``dR = 4.88 cm``, 6.25 m range.

    Returns
    -------
    RadarConfig

    Examples
    --------
    >>> cfg = openradar()
    >>> round(cfg.range_resolution_m * 100, 2), round(cfg.max_range_m, 2)
    (4.88, 6.25)
    """
    return RadarConfig(
        name="openradar", carrier_hz=77.42e9, slope_hz_per_s=60e12, fs_hz=2.5e6,
        n_samples=128, n_chirps=64, chirp_period_s=92e-6, idle_s=30e-6, adc_start_s=6e-6,
        tx_positions_lambda=(0.0, 2.0), rx_positions_lambda=(0.0, 0.5, 1.0, 1.5),
        adc_bits=16, iq=True, frame_rate_hz=10.0,
   )


PRESETS: dict[str, Callable[[], RadarConfig]] = {
    "carrada": carrada,
    "seed003": seed003,
    "openradar": openradar,
}
"""Preset name -> factory returning a fresh :class:`RadarConfig`."""


def preset(name: str) -> RadarConfig:
    """The preset sensor called ``name``.

    Parameters
    ----------
    name : str
        One of ``PRESETS``: ``"carrada"``, ``"seed003"``, ``"openradar"``.

    Returns
    -------
    RadarConfig

    Raises
    ------
    RadarConfigError
        ``name`` is not a preset; the message lists the presets.

    Examples
    --------
    >>> preset("openradar").n_virtual
    8
    >>> preset("ti")
    Traceback (most recent call last):
    ...
    ir.errors.RadarConfigError: unknown radar preset 'ti'; presets: carrada, openradar, seed003
    """
    factory = PRESETS.get(name)
    if factory is None:
        raise RadarConfigError(
            f"unknown radar preset {name!r}; presets: {', '.join(sorted(PRESETS))}"
       )
    return factory()
