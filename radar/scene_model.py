"""The scene records of the FMCW simulator: targets, leakage, clutter, scene, truth, frame.

:func:`radar.scene.simulate_frame` turns a :class:`Scene` into a :class:`Frame`; the
signal model and the conventions (``velocity_mps > 0`` receding, ``azimuth_deg > 0``
phase growing along the element positions) are in :mod:`radar.scene`, which
re-exports every name here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydantic import Field, model_validator

from ir.errors import RadarConfigError
from radar.config import RadarConfig, RadarModel

__all__ = [
    "Clutter",
    "Frame",
    "Leakage",
    "Scene",
    "Target",
    "TargetTruth",
    "target_amplitude_dbfs",
]


class Target(RadarModel):
    """A moving point target; ``velocity_mps`` is radial, positive = receding."""

    range_m: float = Field(gt=0)
    velocity_mps: float = 0.0
    azimuth_deg: float = Field(default=0.0, ge=-90, le=90)
    rcs_dbsm: float = 0.0
    name: str = ""


class Leakage(RadarModel):
    """A static near-range return (Tx->Rx leakage, radome, bumper, DC at ``range_m = 0``).

    The radar equation does not hold this close, so the amplitude is given directly, as a
    peak per-rail amplitude in dBFS; it is identical on every virtual channel.
    ``phase_noise_deg`` is the rms of an independent Gaussian phase per transmitted chirp
    (the oscillator's phase noise the coupling path does not cancel), so the return is
    static over the chirps up to that jitter; 0 (the default) makes it exactly static.
    """

    range_m: float = Field(default=0.0, ge=0)
    amplitude_dbfs: float
    phase_deg: float = 0.0
    phase_noise_deg: float = Field(default=0.0, ge=0, le=180)
    name: str = "leakage"


class Clutter(RadarModel):
    """Static clutter: ``n_scatterers`` still points with random range, azimuth and phase.

    Ranges are uniform in ``[min_range_m, max_range_m]``, azimuths uniform in
    ``+-max_azimuth_deg``, amplitudes complex Gaussian with rms ``amplitude_dbfs``.
    """

    n_scatterers: int = Field(default=32, ge=1, le=1024)
    amplitude_dbfs: float
    min_range_m: float = Field(default=1.0, gt=0)
    max_range_m: float = Field(gt=0)
    max_azimuth_deg: float = Field(default=60.0, ge=0, le=90)

    @model_validator(mode="after")
    def _check_span(self) -> Clutter:
        if self.min_range_m >= self.max_range_m:
            raise RadarConfigError(
                f"Clutter: min_range_m = {self.min_range_m:g} m must be below "
                f"max_range_m = {self.max_range_m:g} m"
            )
        return self


class Scene(RadarModel):
    """What the radar sees, plus the receiver's noise and ADC behaviour.

    ``gain_dbfs`` is the amplitude of a 0 dBsm target at 1 m (see
    :func:`target_amplitude_dbfs`); ``noise_dbfs`` the rms noise per rail (None: no noise);
    ``quantize`` turns ADC rounding and clipping on (the default) or off.
    """

    targets: tuple[Target, ...] = ()
    leakage: tuple[Leakage, ...] = ()
    clutter: Clutter | None = None
    noise_dbfs: float | None = -70.0
    gain_dbfs: float = -20.0
    quantize: bool = True
    name: str = "custom"


class TargetTruth(RadarModel):
    """Ground truth of one target for one frame.

    ``range_bin`` is the nearest bin of the conventional range FFT (peak frequency at
    mid-frame, Doppler shift included); ``doppler_bin`` the observed bin in the fftshifted
    layout, aliased when ``aliased`` (velocity outside ``[-v_max, v_max)``); ``angle_bin``
    the fftshifted bin of an ``n_angle_bins`` FFT over the virtual channels after TDM
    Doppler compensation (None unless the virtual array is a uniform line).
    """

    name: str
    range_m: float
    velocity_mps: float
    azimuth_deg: float
    rcs_dbsm: float
    amplitude_dbfs: float
    range_bin: int
    range_bin_exact: float
    doppler_bin: int
    doppler_bin_exact: float
    aliased: bool
    angle_bin: int | None


@dataclass(frozen=True, eq=False)
class Frame:
    """One simulated frame: the read-only ADC cube and how it was made.

    ``adc`` has shape ``[n_virtual, n_chirps, n_samples]`` (complex128 for IQ configs,
    float64 for real ones) in ADC codes; ``n_clipped`` counts rail values the ADC clipped.
    """

    adc: np.ndarray
    truth: tuple[TargetTruth, ...]
    config: RadarConfig
    scene: Scene
    seed: int
    n_angle_bins: int
    n_clipped: int


def target_amplitude_dbfs(rcs_dbsm: float, range_m: float, gain_dbfs: float) -> float:
    """Peak per-rail amplitude of a target by the radar equation, dBFS.

    ``|a| / FS = 10^(gain_dbfs/20) sqrt(sigma) / R^2`` with ``sigma = 10^(rcs_dbsm/10)`` m^2,
    i.e. ``gain_dbfs + rcs_dbsm - 40 log10(range_m)`` dBFS.

    Parameters
    ----------
    rcs_dbsm : float
        Radar cross-section, dBsm.
    range_m : float
        Range, m (> 0).
    gain_dbfs : float
        Amplitude of a 0 dBsm target at 1 m, dBFS.

    Returns
    -------
    float

    Examples
    --------
    >>> target_amplitude_dbfs(0.0, 10.0, 0.0)
    -40.0
    >>> target_amplitude_dbfs(40.0, 100.0, -20.0)
    -60.0
    """
    return gain_dbfs + rcs_dbsm - 40.0 * float(np.log10(range_m))
