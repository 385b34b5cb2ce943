"""The scenes made for the radar presets (:data:`SCENE_PRESETS`, one per preset name).

Re-exported by :mod:`radar.scene`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from radar.scene_model import Clutter, Leakage, Scene, Target, target_amplitude_dbfs

__all__ = ["SCENE_PRESETS", "carrada_scene", "seed003_scene"]


def seed003_scene() -> Scene:
    """López-Randulfe et al.'s (2021) scene: pedestrians at 5 and 9 m, a car at 100 m, packaging.

    Targets at 5, 9, 100 m moving at 0, 2, 14 m/s with RCS 0, 5, 40 dBsm (paper). The
    20 mm sensor packaging (-40 dBsm) and the 1 cm bumper (-23 dBsm) become near-range
    leakage at 0.02 m and 0.05 m (positions assumed), with the radar-equation amplitude
    at that range (-12.0 and -11.0 dBFS at ``gain_dbfs = -40``). Noise: 1 LSB rms of the
    12-bit ADC (-66.2 dBFS).

    Returns
    -------
    Scene

    Examples
    --------
    >>> [t.range_m for t in seed003_scene().targets]
    [5.0, 9.0, 100.0]
    """
    gain = -40.0
    return Scene(
        name="seed003",
        targets=(Target(range_m=5.0, velocity_mps=0.0, rcs_dbsm=0.0, name="pedestrian_1"),
                 Target(range_m=9.0, velocity_mps=2.0, rcs_dbsm=5.0, name="pedestrian_2"),
                 Target(range_m=100.0, velocity_mps=14.0, rcs_dbsm=40.0, name="car")),
        leakage=(Leakage(range_m=0.02, name="packaging",
                         amplitude_dbfs=target_amplitude_dbfs(-40.0, 0.02, gain)),
                 Leakage(range_m=0.05, name="bumper",
                         amplitude_dbfs=target_amplitude_dbfs(-23.0, 0.05, gain))),
        noise_dbfs=-20 * np.log10(2048.0), gain_dbfs=gain)


def carrada_scene() -> Scene:
    """A street scene for the ``carrada`` preset: car, pedestrian, cyclist, fast car.

    The fast car approaches at 20 m/s, beyond ``v_max = 13.52 m/s``, so its Doppler bin
    aliases. Also Tx->Rx leakage at 0.05 m and 24 static clutter points.

    Returns
    -------
    Scene

    Examples
    --------
    >>> [t.name for t in carrada_scene().targets]
    ['car', 'pedestrian', 'cyclist', 'fast_car']
    """
    return Scene(
        name="carrada",
        targets=(Target(range_m=25.0, velocity_mps=8.0, azimuth_deg=20.0, rcs_dbsm=10.0,
                        name="car"),
                 Target(range_m=8.0, velocity_mps=-1.5, azimuth_deg=-30.0, rcs_dbsm=-5.0,
                        name="pedestrian"),
                 Target(range_m=15.0, velocity_mps=4.0, azimuth_deg=10.0, rcs_dbsm=0.0,
                        name="cyclist"),
                 Target(range_m=40.0, velocity_mps=-20.0, azimuth_deg=-10.0, rcs_dbsm=15.0,
                        name="fast_car")),
        leakage=(Leakage(range_m=0.05, amplitude_dbfs=-30.0, name="tx_rx_leakage"),),
        clutter=Clutter(n_scatterers=24, amplitude_dbfs=-75.0, min_range_m=3.0,
                        max_range_m=48.0),
        noise_dbfs=-80.0, gain_dbfs=-20.0)


SCENE_PRESETS: dict[str, Callable[[], Scene]] = {
    "seed003": seed003_scene,
    "carrada": carrada_scene,
}
"""Radar preset name -> factory of the scene made for it (see :data:`radar.config.PRESETS`)."""
