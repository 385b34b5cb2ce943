r"""Class signatures for the scene simulator: cars, pedestrians and cyclists as point scatterers.

An object is a rigid body moving at ``speed_mps`` along ``heading_deg`` (measured from
the line of sight: 0 = straight away from the radar, 180 = straight towards it), plus
moving parts that give the micro-Doppler of its class. :func:`scatterers` returns,
for one instant ``time_s``, every point's range, radial velocity, azimuth and RCS;
:func:`to_targets` turns them into :class:`radar.scene.Target` records for
:func:`radar.scene.simulate_frame` (the full ADC model), and
:mod:`radar.roi_dataset` synthesises range-Doppler maps from them directly.

Geometry (far field): a point at along-track offset ``x`` and cross-track offset
``y`` from the object's reference point, moving along-track at ``u`` m/s, has

.. math::

    R = R_0 + v_r t + x\cos\psi - y\sin\psi, \qquad v = u\cos\psi,
    \qquad \theta = \theta_0 + \frac{180}{\pi}\,\frac{x\sin\psi + y\cos\psi}{R_0}

with :math:`v_r = s\cos\psi` the body's radial velocity. Moving parts (the along-track
speed ``u`` of each point, :math:`\omega = 2\pi f`):

* **car** — 8 body points on a ``length_m`` x 1.8 m outline, all at ``u = s``; two
  visible wheels (radius 0.32 m) with 6 rim points each, ``u = s(1 - \cos(\phi_i + \omega t))``
  with :math:`\omega = s / r`, i.e. spread over ``[0, 2s]`` but weak (-18 dB).
* **pedestrian** — torso (with the head) at ``s``; two arms ``s(1 + 0.7\sin(\omega t + \phi))``
  and two legs (thigh ``0.5``, foot ``1.0`` amplitude), left and right in antiphase;
  ``f`` = the stride frequency ``0.8 \sqrt{s / 1.4\,\mathrm{m/s}}`` Hz.
* **cyclist** — torso and bicycle frame at ``s``; pedalling feet and knees
  ``s + 2\pi c\, r_p \cos(2\pi c t + \phi)`` with crank ``r_p = 0.17`` m (knees ``0.6 r_p``),
  cadence ``c`` in 1.0-1.6 Hz; two wheels (radius 0.35 m) with 8 rim and spoke points
  each, ``u = s(1 - \rho\cos(\phi_i + \omega t))``, ``\rho`` in (0, 1].

Examples
--------
>>> rng = np.random.default_rng(0)
>>> obj = random_object("pedestrian", rng)
>>> pts = scatterers(obj, time_s=0.0)
>>> pts.size, obj.kind
(7, 'pedestrian')
>>> len(to_targets(pts))
7
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import Field

from ir.errors import RadarConfigError
from radar.config import RadarModel
from radar.scene import Target

__all__ = [
    "CLASSES",
    "SIGNATURES",
    "ObjectState",
    "Scatterers",
    "random_object",
    "scatterers",
    "to_targets",
]

ClassName = Literal["car", "pedestrian", "cyclist"]

#: The classes, in label order (label ``i`` is ``CLASSES[i]``).
CLASSES: tuple[str, ...] = ("car", "pedestrian", "cyclist")


class ObjectState(RadarModel):
    """One object of a class at time 0 (frozen; see the module docstring for the geometry).

    Parameters
    ----------
    kind : {"car", "pedestrian", "cyclist"}
    range_m, azimuth_deg : float
        Position of the reference point at ``t = 0``.
    speed_mps : float
        Speed along the heading (>= 0).
    heading_deg : float
        Direction of motion relative to the line of sight (0 = receding).
    rcs_dbsm : float
        Total RCS; the body points share it (moving parts are set relative to it).
    length_m : float
        Body length (cars: 3.5-5 m; the others' extents are fixed by the model).
    rate_hz : float
        Gait stride frequency (pedestrian) or pedalling cadence (cyclist); unused for cars.
    phase_rad : float
        Phase of the gait or pedalling cycle, and of the wheels, at ``t = 0``.
    """

    kind: ClassName
    range_m: float = Field(gt=0)
    azimuth_deg: float = Field(default=0.0, ge=-90, le=90)
    speed_mps: float = Field(default=0.0, ge=0)
    heading_deg: float = 0.0
    rcs_dbsm: float = 0.0
    length_m: float = Field(default=4.5, gt=0)
    rate_hz: float = Field(default=1.0, gt=0)
    phase_rad: float = 0.0

    @property
    def radial_velocity_mps(self) -> float:
        """The body's radial velocity ``s cos(heading)``, m/s (> 0 receding)."""
        return self.speed_mps * float(np.cos(np.deg2rad(self.heading_deg)))


@dataclass(frozen=True, eq=False)
class Scatterers:
    """Point scatterers of one instant: equal-length float arrays (one entry per point)."""

    range_m: np.ndarray
    velocity_mps: np.ndarray
    azimuth_deg: np.ndarray
    rcs_dbsm: np.ndarray

    @property
    def size(self) -> int:
        """Number of points."""
        return int(self.range_m.size)

    @staticmethod
    def concat(parts: list[Scatterers]) -> Scatterers:
        """All points of ``parts`` in one record.

        Examples
        --------
        >>> one = Scatterers(*(np.ones(2) for _ in range(4)))
        >>> Scatterers.concat([one, one]).size
        4
        """
        return Scatterers(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                            ("range_m", "velocity_mps", "azimuth_deg", "rcs_dbsm")))


# --------------------------------------------------------------------------- parts
# Each class model returns (x, y, u, rcs_rel_db): along/cross-track offsets (m), along-track
# speed (m/s) and RCS relative to the object's total, for every point at time t.
_Parts = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _wheel(center_x: float, y: float, radius_m: float, rho: np.ndarray, phi0: np.ndarray,
           speed: float, t: float, phase: float, rcs_db: float) -> _Parts:
    """Rim/spoke points of a rolling wheel: along-track speed ``s (1 - rho cos(phi))``."""
    phi = phi0 + speed / radius_m * t + phase
    x = center_x + rho * radius_m * np.sin(phi)
    u = speed * (1.0 - rho * np.cos(phi))
    n = rho.size
    return x, np.full(n, y), u, np.full(n, rcs_db)


def _car(obj: ObjectState, t: float) -> _Parts:
    half_l, half_w = obj.length_m / 2, 0.9
    x = np.array([half_l, half_l, -half_l, -half_l, 0.35 * half_l, -0.1 * half_l,
                  0.6 * half_l, -0.6 * half_l])
    y = np.array([-0.6, 0.6, -0.6, 0.6, -half_w, -half_w, -half_w, half_w])
    rel = np.array([-6.0, -6.0, -8.0, -8.0, -9.0, -10.0, -11.0, -11.0])
    body = (x, y, np.full(x.size, obj.speed_mps), rel)
    phi0 = np.linspace(0.0, 2 * np.pi, 6, endpoint=False)
    wheels = [_wheel(cx, -half_w, 0.32, np.ones(6), phi0, obj.speed_mps, t, obj.phase_rad,
                     -26.0) for cx in (0.6 * half_l, -0.6 * half_l)]
    return _stack([body, *wheels])


def _pedestrian(obj: ObjectState, t: float) -> _Parts:
    s, w = obj.speed_mps, 2 * np.pi * obj.rate_hz * t + obj.phase_rad
    side = np.array([0.0, np.pi])
    amp = np.array([0.0, 0.0, 0.7, 0.7, 0.5, 0.5, 1.0, 1.0])
    ph = np.concatenate([[0.0, 0.0], np.pi + side, side, side])
    u = s * (1.0 + amp * np.sin(w + ph))
    x = np.array([0.0, 0.0, 0.15, -0.15, 0.1, -0.1, 0.3, -0.3]) * np.sin(w + ph)
    y = np.array([0.0, 0.0, -0.25, 0.25, -0.1, 0.1, -0.1, 0.1])
    rel = np.array([-1.5, -9.0, -11.0, -11.0, -9.0, -9.0, -12.0, -12.0])
    # head and torso share a range/velocity cell: fold the head into the torso's RCS
    rel = rel.copy()
    rel[0] = 10 * np.log10(10 ** (rel[0] / 10) + 10 ** (rel[1] / 10))
    keep = np.array([0, 2, 3, 4, 5, 6, 7])
    return x[keep], y[keep], u[keep], rel[keep]


def _cyclist(obj: ObjectState, t: float) -> _Parts:
    s, c = obj.speed_mps, obj.rate_hz
    crank = 2 * np.pi * c * t + obj.phase_rad + np.array([0.0, np.pi, 0.0, np.pi])
    r_p = 0.17 * np.array([1.0, 1.0, 0.6, 0.6])
    legs_u = s + 2 * np.pi * c * r_p * np.cos(crank)
    legs = (0.1 + r_p * np.sin(crank), np.array([-0.12, 0.12, -0.15, 0.15]), legs_u,
            np.array([-11.0, -11.0, -12.0, -12.0]))
    body = (np.array([0.0, 0.1]), np.array([0.0, 0.0]), np.full(2, s), np.array([-3.0, -4.5]))
    rho = np.array([1.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.75, 0.75])
    phi0 = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
    wheels = [_wheel(cx, 0.0, 0.35, rho, phi0 + k, s, t, obj.phase_rad, -14.0)
              for k, cx in enumerate((0.55, -0.55))]
    return _stack([body, legs, *wheels])


def _stack(parts: list[_Parts]) -> _Parts:
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(4))  # type: ignore[return-value]


#: Class name -> model of its points (along, cross, along-track speed, relative RCS dB).
SIGNATURES: dict[str, Callable[[ObjectState, float], _Parts]] = {
    "car": _car, "pedestrian": _pedestrian, "cyclist": _cyclist,
}


def scatterers(obj: ObjectState, time_s: float,
               signatures: dict[str, Callable[[ObjectState, float], _Parts]] = SIGNATURES,
               ) -> Scatterers:
    """The object's point scatterers at ``time_s`` (see the module docstring).

    Parameters
    ----------
    obj : ObjectState
        The object at ``t = 0``.
    time_s : float
        The instant (the body moves radially at ``obj.radial_velocity_mps``).
    signatures : dict, optional
        Class models by name (default :data:`SIGNATURES`).

    Returns
    -------
    Scatterers

    Raises
    ------
    RadarConfigError
        If the class has no model, or a point's range is not positive.

    Examples
    --------
    A car receding at 10 m/s: every body point moves at 10 m/s, the wheel rims between 0 and 20.

    >>> car = ObjectState(kind="car", range_m=20.0, speed_mps=10.0, rcs_dbsm=10.0)
    >>> v = scatterers(car, 0.0).velocity_mps
    >>> v[:8].tolist() == [10.0] * 8, bool(v.min() >= 0.0 and v.max() <= 20.0)
    (True, True)
    """
    if obj.kind not in signatures:
        raise RadarConfigError(f"scatterers: no signature for class {obj.kind!r}; known: "
                               f"{sorted(signatures)}")
    x, y, u, rel = signatures[obj.kind](obj, float(time_s))
    psi = np.deg2rad(obj.heading_deg)
    rng = obj.range_m + obj.radial_velocity_mps * time_s + x * np.cos(psi) - y * np.sin(psi)
    if rng.min() <= 0:
        raise RadarConfigError(f"scatterers: object {obj.kind!r} reaches range "
                               f"{rng.min():.3g} m <= 0 at t = {time_s:g} s; start it further "
                               "away or shorten the sequence")
    az = obj.azimuth_deg + np.rad2deg((x * np.sin(psi) + y * np.cos(psi)) / obj.range_m)
    return Scatterers(range_m=rng, velocity_mps=u * np.cos(psi),
                      azimuth_deg=np.clip(az, -90.0, 90.0), rcs_dbsm=obj.rcs_dbsm + rel)


def to_targets(points: Scatterers, name: str = "") -> tuple[Target, ...]:
    """The points as :class:`radar.scene.Target` records (for ``simulate_frame``).

    Examples
    --------
    >>> pts = Scatterers(np.array([10.0]), np.array([1.0]), np.array([5.0]), np.array([0.0]))
    >>> to_targets(pts, "ped")[0].velocity_mps
    1.0
    """
    return tuple(Target(range_m=float(r), velocity_mps=float(v), azimuth_deg=float(a),
                        rcs_dbsm=float(s), name=f"{name}{i}")
                 for i, (r, v, a, s) in enumerate(zip(points.range_m, points.velocity_mps,
                                                      points.azimuth_deg, points.rcs_dbsm,
                                                      strict=True)))


#: Per class: speed (m/s), total RCS (dBsm), length (m), rate (Hz) ranges drawn uniformly.
_RANDOM: dict[str, dict[str, tuple[float, float]]] = {
    "car": {"speed": (3.0, 12.0), "rcs": (5.0, 20.0), "length": (3.6, 5.0), "rate": (1.0, 1.0)},
    "pedestrian": {"speed": (0.8, 2.2), "rcs": (-8.0, 0.0), "length": (0.5, 0.5),
                   "rate": (0.7, 1.1)},
    "cyclist": {"speed": (2.5, 7.0), "rcs": (-5.0, 3.0), "length": (1.8, 1.8),
                "rate": (1.0, 1.6)},
}


def random_object(kind: str, rng: np.random.Generator, *, range_m: tuple[float, float] = (
                  4.0, 40.0), azimuth_deg: float = 40.0, max_off_axis_deg: float = 60.0,
                  ) -> ObjectState:
    """A random object of class ``kind``: position, speed, heading, RCS and gait drawn uniformly.

    The heading is within ``max_off_axis_deg`` of the line of sight, towards or away
    from the radar, so the body's radial speed is at least ``cos(max_off_axis_deg)``
    of its speed (objects crossing at right angles have no radial velocity and sit in
    the static clutter).

    Examples
    --------
    >>> o = random_object("cyclist", np.random.default_rng(1))
    >>> 2.5 <= o.speed_mps <= 7.0, abs(o.radial_velocity_mps) >= 0.5 * o.speed_mps - 1e-12
    (True, True)
    """
    if kind not in _RANDOM:
        raise RadarConfigError(f"random_object: unknown class {kind!r}; use one of {CLASSES}")
    p = _RANDOM[kind]
    off = rng.uniform(-max_off_axis_deg, max_off_axis_deg)
    heading = off + (180.0 if rng.random() < 0.5 else 0.0)
    return ObjectState(
        kind=kind, range_m=rng.uniform(*range_m), azimuth_deg=rng.uniform(-azimuth_deg,
                                                                          azimuth_deg),
        speed_mps=rng.uniform(*p["speed"]), heading_deg=heading, rcs_dbsm=rng.uniform(*p["rcs"]),
        length_m=rng.uniform(*p["length"]), rate_hz=rng.uniform(*p["rate"]),
        phase_rad=rng.uniform(0.0, 2 * np.pi))
