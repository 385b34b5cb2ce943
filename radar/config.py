"""FMCW radar configuration: the sensor's parameters, its derived resolutions, and presets.

A :class:`RadarConfig` describes one FMCW sensor and one frame of TDM-MIMO chirps. Every
field carries its unit in its name; every derived quantity is a property whose docstring
gives its formula. Resolutions follow from the *sampled* bandwidth, the part of the sweep
the ADC actually sees: ``B_s = slope_hz_per_s * n_samples / fs_hz``. The record itself is
in :mod:`radar.sensor`; this module holds the presets and re-exports the record.

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

from ir.errors import RadarConfigError
from radar.sensor import SPEED_OF_LIGHT_MPS, RadarConfig, RadarModel

__all__ = [
    "SPEED_OF_LIGHT_MPS",
    "PRESETS",
    "RadarConfig",
    "RadarModel",
    "carrada",
    "chirpseq",
    "mimo77",
    "openradar",
    "preset",
    "seed003",
]

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


def mimo77() -> RadarConfig:
    """A 77 GHz 3 Tx x 4 Rx TDM-MIMO front end with a 12-bit IQ ADC: 256 samples x 128 chirps.

    Slope 30 MHz/us at 10 Msps gives ``B_s = 768 MHz``, ``dR = 0.1952 m`` and 49.96 m of
    range; ``T_c = 40 us`` and three Tx slots give ``v_max = 8.11 m/s`` and
    ``dv = 0.1267 m/s`` (frame 15.36 ms, 20 frames/s). Tx at 0, 2 and 4 lambda with Rx at
    lambda/2 make a uniform 12-element virtual line. The numbers are assumptions of the
    automotive single-chip class (3 Tx, 4 Rx, 12-bit ADC), not one product's datasheet;
    the 12-bit ADC clips at ``[-2048, 2047]`` codes per rail.

    Returns
    -------
    RadarConfig

    Examples
    --------
    >>> cfg = mimo77()
    >>> cfg.n_virtual, cfg.full_scale_code, round(cfg.max_velocity_mps, 2)
    (12, 2048, 8.11)
    """
    return RadarConfig(
        name="mimo77", carrier_hz=77e9, slope_hz_per_s=30e12, fs_hz=10e6, n_samples=256,
        n_chirps=128, chirp_period_s=40e-6, idle_s=8e-6, adc_start_s=4e-6,
        tx_positions_lambda=(0.0, 2.0, 4.0), rx_positions_lambda=(0.0, 0.5, 1.0, 1.5),
        adc_bits=12, iq=True, frame_rate_hz=20.0,
    )


def chirpseq() -> RadarConfig:
    """A slow 1 Tx x 1 Rx chirp sequence: 201 chirps x 512 real samples, one chirp per ms.

    Slope 10 MHz/us at 5 Msps (real) gives ``B_s = 1.024 GHz``, ``dR = 0.1464 m``, 256
    positive range bins up to 37.47 m; a chirp every millisecond (110 us ramp) makes the
    201-chirp sequence last 201 ms (4 sequences/s), long enough for a target at a few m/s
    to cross several range bins. Made for chains without a Doppler DFT (range + CFAR per
    chirp); 12-bit ADC. All numbers are assumptions.

    Returns
    -------
    RadarConfig

    Examples
    --------
    >>> cfg = chirpseq()
    >>> cfg.n_chirps, cfg.n_range_bins, round(cfg.range_resolution_m, 4)
    (201, 256, 0.1464)
    """
    return RadarConfig(
        name="chirpseq", carrier_hz=77e9, slope_hz_per_s=10e12, fs_hz=5e6, n_samples=512,
        n_chirps=201, chirp_period_s=1e-3, idle_s=890e-6, adc_start_s=5e-6,
        adc_bits=12, iq=False, frame_rate_hz=4.0,
    )


PRESETS: dict[str, Callable[[], RadarConfig]] = {
    "carrada": carrada,
    "seed003": seed003,
    "openradar": openradar,
    "mimo77": mimo77,
    "chirpseq": chirpseq,
}
"""Preset name -> factory returning a fresh :class:`RadarConfig`."""


def preset(name: str) -> RadarConfig:
    """The preset sensor called ``name``.

    Parameters
    ----------
    name : str
        One of ``PRESETS``: ``"carrada"``, ``"seed003"``, ``"openradar"``, ``"mimo77"``,
        ``"chirpseq"``.

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
    >>> preset("ti")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ir.errors.RadarConfigError: unknown radar preset 'ti'; presets: carrada, chirpseq, ..., seed003
    """
    factory = PRESETS.get(name)
    if factory is None:
        raise RadarConfigError(
            f"unknown radar preset {name!r}; presets: {', '.join(sorted(PRESETS))}"
       )
    return factory()
