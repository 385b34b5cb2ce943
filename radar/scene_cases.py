"""Scene cases that are hard in the way real sensors are, drawn afresh for every seed.

A :class:`SceneCase` names what it tests, the sensor preset it runs on and a draw: the
seed picks the targets (positions, velocities, levels) as well as the clutter and noise,
so frames of different seeds differ in content, and calibration frames (one set of seeds)
never hold the targets of the frames measured (another set). :data:`SCENE_CASES`:

* ``leaky_mimo`` — ``mimo77``, 36 targets spread over range and Doppler, 32 of them
  40–70 dB and 4 of them 15–30 dB below a Tx→Rx coupling at range 0 (with chirp phase
  noise) and a radome return at 1.5 bins, 48 static clutter points at zero Doppler,
  thermal noise from a 14 dB noise figure;
* ``saturated_mimo`` — the same without the 4 strong targets and the coupling 5.1 dB
  louder: the 12-bit ADC clips (0.03–0.17 % of the rail samples on seeds 0–2);
* ``high_noise`` — ``mimo77``, 12 targets 16–21 dB above the noise in their range-Doppler
  cell (0–5 dB above the default OS-CFAR's threshold on the 12-receiver sum), a receiver
  12 dB noisier, weaker leakage;
* ``range_migration`` — ``mimo77``, 8 targets at 25–60 m/s that cross 2–5 range bins over
  the frame (Doppler aliased);
* ``chirp_sequence_1d`` — ``chirpseq``, one target crossing 4–8 range bins over 201 chirps,
  near-range leakage ≈ 50 dB above it: for range + CFAR per chirp, no Doppler DFT.

Levels are per-rail amplitudes in dBFS; a target's is turned into the RCS that gives it
by the radar equation (:func:`radar.scene_model.target_amplitude_dbfs`).

Examples
--------
>>> case = SCENE_CASES["leaky_mimo"]
>>> case.sensor, len(case.scene(0).targets)
('mimo77', 36)
>>> case.scene(0).targets[0] == case.scene(1).targets[0]
False
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ir.errors import RadarConfigError
from radar.config import RadarConfig, preset
from radar.scene import Frame, simulate_frame
from radar.scene_model import Clutter, Leakage, Scene, Target

__all__ = [
    "SCENE_CASES",
    "SceneCase",
    "cell_snr_db",
    "receiver_noise_dbfs",
]

_DRAW_KEY = 34  # a fixed second key: the draws' stream is apart from the simulator's
_BOLTZMANN_DBM_PER_HZ = -174.0  # kT at 290 K, dBm/Hz
_HANN_ENBW = 1.5  # equivalent noise bandwidth of a Hann window, bins


def receiver_noise_dbfs(config: RadarConfig, *, noise_figure_db: float, gain_db: float,
                        full_scale_dbm: float) -> float:
    """Thermal noise per ADC rail, dBFS (the ``Scene.noise_dbfs`` it gives).

    ``P_n = -174 dBm/Hz + 10 log10(fs) + NF + G`` at the ADC, split over the two rails of
    IQ sampling (−3.01 dB each), referred to ``full_scale_dbm`` (the power of a rail held
    at full scale): ``noise_dbfs = P_n [- 3.01] - full_scale_dbm``.

    Parameters
    ----------
    config : RadarConfig
        The sensor (``fs_hz`` is the noise bandwidth; ``iq`` the split over rails).
    noise_figure_db, gain_db, full_scale_dbm : float
        Receiver noise figure, gain from antenna to ADC, and ADC full scale (assumptions
        of each case, stated there).

    Returns
    -------
    float

    Examples
    --------
    >>> round(receiver_noise_dbfs(preset("mimo77"), noise_figure_db=14.0, gain_db=38.0,
    ...                           full_scale_dbm=10.0), 2)
    -65.01
    """
    p_n = _BOLTZMANN_DBM_PER_HZ + 10 * np.log10(config.fs_hz) + noise_figure_db + gain_db
    return float(p_n - (10 * np.log10(2) if config.iq else 0.0) - full_scale_dbm)


def cell_snr_db(config: RadarConfig, amplitude_dbfs: float, noise_dbfs: float, *,
                doppler: bool = True) -> float:
    """SNR of an on-bin target in its cell of the Hann-windowed range(-Doppler) map.

    A tone of per-rail amplitude ``A`` in noise of rms ``sigma`` per rail, after a window
    of equivalent noise bandwidth ``B`` bins over ``L`` samples: ``|A|^2 L / (2 sigma^2 B)``
    for IQ, ``|A|^2 L / (4 sigma^2 B)`` for real sampling (half the tone in the positive
    half). ``L = N M`` and ``B = 1.5^2`` with the Doppler DFT, ``L = N``, ``B = 1.5``
    without. Per channel; the sum over receivers keeps the ratio of means.

    Examples
    --------
    >>> round(cell_snr_db(preset("mimo77"), -80.0, -60.0), 2)
    18.62
    """
    n = config.n_samples * (config.n_chirps if doppler else 1)
    enbw = _HANN_ENBW ** (2 if doppler else 1)
    rails = 2.0 if config.iq else 4.0
    return float(amplitude_dbfs - noise_dbfs + 10 * np.log10(n / (rails * enbw)))


@dataclass(frozen=True)
class SceneCase:
    """A named hard scene: what it tests, its sensor preset and its seeded draw.

    Attributes
    ----------
    name : str
        What it tests, e.g. ``leaky_mimo``.
    sensor : str
        The :func:`radar.config.preset` it runs on.
    summary : str
        One line: the physics it stresses.
    draw : callable
        ``draw(config, rng) -> Scene``; :meth:`scene` seeds ``rng`` from the seed.
    """

    name: str
    sensor: str
    summary: str
    draw: Callable[[RadarConfig, np.random.Generator], Scene]

    def config(self) -> RadarConfig:
        """A fresh copy of the sensor."""
        return preset(self.sensor)

    def scene(self, seed: int) -> Scene:
        """The scene of ``seed``: targets drawn from ``default_rng([seed, 34])``.

        The draw's stream is not the simulator's (``default_rng(seed)``, clutter and
        noise), so the targets do not correlate with the noise of the same seed.
        """
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise RadarConfigError(f"SceneCase '{self.name}': seed must be a non-negative "
                                   f"int, got {seed!r}")
        scene = self.draw(self.config(), np.random.default_rng([int(seed), _DRAW_KEY]))
        return scene.model_copy(update={"name": f"{self.name}-{seed}"})

    def frame(self, seed: int) -> Frame:
        """The simulated frame of ``seed`` (:func:`radar.scene.simulate_frame`)."""
        return simulate_frame(self.config(), self.scene(seed), seed=seed)

    def cube(self, seeds: Sequence[int]) -> np.ndarray:
        """The ADC cubes of ``seeds`` stacked on a new first axis (calibration inputs).

        Examples
        --------
        >>> SCENE_CASES["chirp_sequence_1d"].cube([100, 101]).shape
        (2, 1, 201, 512)
        """
        return np.stack([self.frame(s).adc for s in seeds])


def _spread(rng: np.random.Generator, n: int, n_range: int, n_doppler: int, *,
            min_range_bin: float, min_doppler_gap: float) -> np.ndarray:
    """``n`` (range bin, Doppler bin) positions, uniform, off zero Doppler, apart.

    Two targets are at least 12 range bins or 7 Doppler bins apart (outside each other's
    CFAR window of :data:`compiler.chains.DEFAULT_CFAR`), and every target is at least
    ``min_doppler_gap`` bins from zero Doppler (``n_doppler // 2``, the clutter).
    """
    out: list[tuple[float, float]] = []
    zero = n_doppler // 2
    for _ in range(200 * n):
        r = rng.uniform(min_range_bin, n_range - 8)
        d = rng.uniform(0, n_doppler)
        if abs(d - zero) < min_doppler_gap:
            continue
        if all(abs(r - r2) >= 12 or min(abs(d - d2), n_doppler - abs(d - d2)) >= 7
               for r2, d2 in out):
            out.append((r, d))
            if len(out) == n:
                return np.asarray(out)
    raise RadarConfigError(f"could not place {n} targets apart on a {n_range} x {n_doppler} "
                           "map; lower the number of targets")


def _targets(config: RadarConfig, rng: np.random.Generator, bins: np.ndarray,
             levels_dbfs: np.ndarray, gain_dbfs: float, *, max_azimuth_deg: float = 50.0
             ) -> tuple[Target, ...]:
    """Targets at (range bin, Doppler bin) with per-rail amplitudes ``levels_dbfs``."""
    m = config.n_chirps
    out = []
    for i, ((r, d), level) in enumerate(zip(bins, levels_dbfs, strict=True)):
        range_m = float(r * config.range_resolution_m)
        velocity = float((d - m // 2) * config.velocity_resolution_mps)
        out.append(Target(range_m=range_m, velocity_mps=velocity,
                          azimuth_deg=float(rng.uniform(-max_azimuth_deg, max_azimuth_deg)),
                          rcs_dbsm=float(level - gain_dbfs + 40 * np.log10(range_m)),
                          name=f"t{i}"))
    return tuple(out)


_GAIN_DBFS = -20.0  # radar-equation constant of the mimo77 cases (only sets the RCS figures)


def _mimo_noise(config: RadarConfig, noise_figure_db: float = 14.0) -> float:
    # assumptions: 38 dB receive gain, ADC full scale +10 dBm: -65 dBFS at NF 14 dB (~1.2 LSB)
    return receiver_noise_dbfs(config, noise_figure_db=noise_figure_db, gain_db=38.0,
                               full_scale_dbm=10.0)


def _leakage(config: RadarConfig, coupling_dbfs: float, phase_noise_deg: float = 0.05,
             ) -> tuple[Leakage, ...]:
    """Tx->Rx coupling at range 0 and a radome return at 1.5 range bins, 6 dB below it."""
    return (Leakage(range_m=0.0, amplitude_dbfs=coupling_dbfs, phase_deg=30.0,
                    phase_noise_deg=phase_noise_deg, name="coupling"),
            Leakage(range_m=1.5 * config.range_resolution_m, amplitude_dbfs=coupling_dbfs - 6,
                    phase_deg=-70.0, phase_noise_deg=phase_noise_deg, name="radome"))


def _leaky(config: RadarConfig, rng: np.random.Generator, coupling_dbfs: float = -8.0,
           n_strong: int = 4) -> Scene:
    """36 targets: ``n_strong`` 15-30 dB below the coupling (a car close ahead), the others
    40-70 dB below it."""
    bins = _spread(rng, 36, config.n_range_bins, config.n_chirps, min_range_bin=8,
                   min_doppler_gap=4)
    levels = coupling_dbfs - np.concatenate([rng.uniform(15.0, 30.0, n_strong),
                                             rng.uniform(40.0, 70.0, len(bins) - n_strong)])
    clutter = Clutter(n_scatterers=48, amplitude_dbfs=-62.0, min_range_m=2.0,
                      max_range_m=0.95 * config.max_range_m)
    return Scene(targets=_targets(config, rng, bins, levels, _GAIN_DBFS),
                 leakage=_leakage(config, coupling_dbfs), clutter=clutter,
                 noise_dbfs=_mimo_noise(config), gain_dbfs=_GAIN_DBFS)


def _saturated(config: RadarConfig, rng: np.random.Generator) -> Scene:
    # no strong targets: their intermodulation with the clipped coupling would be ghosts
    return _leaky(config, rng, coupling_dbfs=-2.9, n_strong=0)


def _high_noise(config: RadarConfig, rng: np.random.Generator) -> Scene:
    noise = _mimo_noise(config, noise_figure_db=26.0)
    bins = _spread(rng, 12, config.n_range_bins, config.n_chirps, min_range_bin=8,
                   min_doppler_gap=4)
    offset = cell_snr_db(config, 0.0, noise)  # the SNR of a 0 dBFS tone
    levels = rng.uniform(16.0, 21.0, len(bins)) - offset
    return Scene(targets=_targets(config, rng, bins, levels, _GAIN_DBFS),
                 leakage=_leakage(config, -30.0), noise_dbfs=noise, gain_dbfs=_GAIN_DBFS)


def _migrating(config: RadarConfig, rng: np.random.Generator) -> Scene:
    n = 8
    speed = rng.uniform(25.0, 60.0, n) * rng.choice([-1.0, 1.0], n)
    travel_m = np.abs(speed) * config.frame_time_s
    lo = 10 * config.range_resolution_m + travel_m
    hi = config.max_range_m - 10 * config.range_resolution_m - travel_m
    start = rng.uniform(lo, hi)
    noise = _mimo_noise(config)
    levels = rng.uniform(25.0, 40.0, n) - cell_snr_db(config, 0.0, noise)
    targets = tuple(Target(range_m=float(r), velocity_mps=float(v),
                           azimuth_deg=float(rng.uniform(-30, 30)),
                           rcs_dbsm=float(a - _GAIN_DBFS + 40 * np.log10(r)), name=f"t{i}")
                    for i, (r, v, a) in enumerate(zip(start, speed, levels, strict=True)))
    return Scene(targets=targets, leakage=_leakage(config, -20.0), noise_dbfs=noise,
                 gain_dbfs=_GAIN_DBFS)


def _chirp_sequence(config: RadarConfig, rng: np.random.Generator) -> Scene:
    # assumptions: NF 12 dB, 56 dB gain (the leakage near full scale, as a gain control
    # would set it), full scale +10 dBm: -49 dBFS per rail (~7 LSB)
    noise = receiver_noise_dbfs(config, noise_figure_db=12.0, gain_db=56.0,
                                full_scale_dbm=10.0)
    snr = rng.uniform(12.0, 16.0)
    level = snr - cell_snr_db(config, 0.0, noise, doppler=False)
    start = rng.uniform(8.0, 25.0)
    speed = rng.uniform(3.0, 6.0) * rng.choice([-1.0, 1.0])
    gain = -30.0
    target = Target(range_m=float(start), velocity_mps=float(speed),
                    rcs_dbsm=float(level - gain + 40 * np.log10(start)), name="mover")
    leak = Leakage(range_m=0.05, amplitude_dbfs=float(level + 50.0), phase_deg=20.0,
                   phase_noise_deg=0.05, name="near_range")
    return Scene(targets=(target,), leakage=(leak,), noise_dbfs=noise, gain_dbfs=gain)


SCENE_CASES: dict[str, SceneCase] = {case.name: case for case in (
    SceneCase("leaky_mimo", "mimo77", "36 targets 15-70 dB below near-range leakage "
              "(32 of them 40-70 dB), static clutter, 12-bit ADC", _leaky),
    SceneCase("saturated_mimo", "mimo77", "leaky_mimo without its 4 strong targets and the "
              "coupling at -2.9 dBFS: the ADC clips", _saturated),
    SceneCase("high_noise", "mimo77", "12 targets 16-21 dB above the noise of a 26 dB "
              "noise-figure receiver", _high_noise),
    SceneCase("range_migration", "mimo77", "8 targets at 25-60 m/s crossing 2-5 range bins "
              "in the frame", _migrating),
    SceneCase("chirp_sequence_1d", "chirpseq", "one target crossing range bins over 201 "
              "chirps, leakage 50 dB above it, no Doppler DFT", _chirp_sequence),
)}
"""Case name -> :class:`SceneCase` (see the module docstring for what each tests)."""
