r"""Multi-target tracking: constant-velocity Kalman filters, gated nearest-neighbour association.

Each frame brings a cluster table (:mod:`radar.clustering`): rows of centroid
range and Doppler bins.  A row becomes a measurement of range and radial
velocity,

.. math:: z = \big(\Delta_R\, b_r,\; \Delta_v (b_d - b_0)\big)
          \quad [\mathrm{m}, \mathrm{m/s}],

with the bin widths :math:`\Delta_R, \Delta_v` and the zero-velocity Doppler bin
:math:`b_0` (``M // 2`` after fftshift).  A track's state is
:math:`x = (r, \dot r)` (positive :math:`\dot r`: receding, as the Doppler sign).

Kalman filter (per track, vectorized over tracks).  With frame period
:math:`\Delta t` and white acceleration noise of standard deviation
:math:`\sigma_a`:

.. math:: F = \begin{pmatrix}1 & \Delta t\\ 0 & 1\end{pmatrix}, \quad
          Q = \sigma_a^2 \begin{pmatrix}\Delta t^4/4 & \Delta t^3/2\\
          \Delta t^3/2 & \Delta t^2\end{pmatrix}, \quad H = I, \quad
          R = \mathrm{diag}(\sigma_r^2, \sigma_v^2),

predict :math:`x^- = F x,\ P^- = F P F^\top + Q`; innovation
:math:`\nu = z - x^-`, :math:`S = P^- + R`; update
:math:`K = P^- S^{-1},\ x = x^- + K\nu,\ P = (I - K) P^- (I - K)^\top + K R K^\top`
(Joseph form).

Association.  The squared Mahalanobis distance
:math:`d^2_{ij} = \nu_{ij}^\top S_i^{-1} \nu_{ij}` of every (track, measurement)
pair is gated by :math:`d^2 \le \gamma` (``gate``; 9.21 is the 99 % point of
:math:`\chi^2_2`).  Among the gated pairs, a one-to-one assignment minimising the
summed :math:`d^2` (global nearest neighbour,
:func:`scipy.optimize.linear_sum_assignment`, gated-out pairs cost more than any
set of gated ones, so the assignment has as many pairs as possible) updates the
tracks.

Track management.
* **Birth**: every valid row left unassigned opens a *tentative* track in the
  lowest free slot, in table order (strongest cluster first), with
  :math:`x = z`, :math:`P = R`; rows that find no free slot are dropped.
* **Confirmation**: a track is *confirmed* once it has ``confirm_hits``
  associated frames (its birth counts as one).
* **Deletion**: a tentative track dies at its first miss; a confirmed track
  coasts (predicted, not updated) and dies when ``max_misses`` consecutive frames
  went without a measurement.
* A track keeps its slot (the output row) and its id (1, 2, … in birth order)
  for its whole life.

Output table per frame: ``[max_tracks, N_STATE]`` with columns :data:`STATE`;
free slots are all zero.

Limits: velocities beyond the unambiguous :math:`\pm v_{max}` are measured
aliased, so such a target's range rate contradicts its measured velocity and its
tracks do not survive the gate; no angle, so targets at equal range and
velocity merge.

Examples
--------
>>> import numpy as np
>>> row = lambda r, d: [1.0, r, d, 1.0, 1.0]
>>> tables = np.array([[row(10.0, 2.0)], [row(10.2, 2.0)], [row(10.4, 2.0)]])
>>> out = track_sequence(tables, dt_s=0.1, range_bin_m=1.0, velocity_bin_mps=1.0,
...                      max_tracks=2)
>>> out[:, 0, :3].tolist()          # valid, id, confirmed of slot 0
[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]]
"""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError
from radar.clustering import N_FEATURES

__all__ = ["STATE", "N_STATE", "Tracker", "track_sequence"]

STATE: tuple[str, ...] = ("valid", "id", "confirmed", "range_m", "velocity_mps", "hits",
                          "misses")
"""Columns of a track table (ranges in m, velocities in m/s, counts in frames; the IR's
:data:`ir.ops.host.TRACK_STATE` is this tuple: the domain owns the layout)."""

N_STATE = len(STATE)

#: Cost of a gated-out pair in the assignment (above any sum of gated distances).
_FORBIDDEN = 1e12


class Tracker:
    """Stateful multi-target tracker; call :meth:`update` once per frame (module docstring).

    Parameters
    ----------
    dt_s : float
        Frame period :math:`\\Delta t` (> 0), s.
    range_bin_m, velocity_bin_mps : float
        Range and Doppler bin widths :math:`\\Delta_R, \\Delta_v` (> 0).
    doppler_zero_bin : float
        Doppler bin of zero velocity :math:`b_0`.
    max_tracks : int
        Track slots (rows of the output).
    gate : float
        :math:`\\chi^2` gate :math:`\\gamma` on :math:`d^2` (> 0).
    confirm_hits, max_misses : int
        Confirmation and deletion rules (>= 1).
    accel_std_mps2 : float
        :math:`\\sigma_a`, m/s² (>= 0).
    range_std_m, velocity_std_mps : float, optional
        Measurement noise :math:`\\sigma_r, \\sigma_v` (default half a bin each).

    Raises
    ------
    RadarConfigError
        A parameter out of range.

    Examples
    --------
    >>> trk = Tracker(dt_s=0.1, range_bin_m=0.2, velocity_bin_mps=0.5, doppler_zero_bin=32)
    >>> out = trk.update(np.array([[1.0, 50.0, 36.0, 3.0, 9.0]]))
    >>> out[0, :5].round(3).tolist()      # valid, id, confirmed, 10 m, +2 m/s
    [1.0, 1.0, 0.0, 10.0, 2.0]
    """

    def __init__(self, dt_s: float, *, range_bin_m: float = 1.0,
                 velocity_bin_mps: float = 1.0, doppler_zero_bin: float = 0.0,
                 max_tracks: int = 16, gate: float = 9.21, confirm_hits: int = 3,
                 max_misses: int = 3, accel_std_mps2: float = 2.0,
                 range_std_m: float | None = None,
                 velocity_std_mps: float | None = None) -> None:
        sr = 0.5 * range_bin_m if range_std_m is None else range_std_m
        sv = 0.5 * velocity_bin_mps if velocity_std_mps is None else velocity_std_mps
        checks = {"dt_s": dt_s > 0, "range_bin_m": range_bin_m > 0,
                  "velocity_bin_mps": velocity_bin_mps > 0, "max_tracks": max_tracks >= 1,
                  "gate": gate > 0, "confirm_hits": confirm_hits >= 1,
                  "max_misses": max_misses >= 1, "accel_std_mps2": accel_std_mps2 >= 0,
                  "range_std_m": sr > 0, "velocity_std_mps": sv > 0}
        bad = [k for k, ok in checks.items() if not ok]
        if bad:
            raise RadarConfigError(f"Tracker: {bad} out of range (dt_s, bins, gate and stds must "
                                   "be > 0; max_tracks, confirm_hits, max_misses >= 1; "
                                   "accel_std_mps2 >= 0)")
        self.scale = np.array([range_bin_m, velocity_bin_mps])
        self.doppler_zero_bin = float(doppler_zero_bin)
        self.gate, self.confirm_hits, self.max_misses = gate, confirm_hits, max_misses
        self.F = np.array([[1.0, dt_s], [0.0, 1.0]])
        self.Q = accel_std_mps2**2 * np.array([[dt_s**4 / 4, dt_s**3 / 2],
                                               [dt_s**3 / 2, dt_s**2]])
        self.R = np.diag([sr**2, sv**2])
        self.x = np.zeros((max_tracks, 2))
        self.P = np.tile(self.R, (max_tracks, 1, 1))
        self.alive = np.zeros(max_tracks, dtype=bool)
        self.ids = np.zeros(max_tracks, dtype=np.int64)
        self.hits = np.zeros(max_tracks, dtype=np.int64)
        self.misses = np.zeros(max_tracks, dtype=np.int64)
        self.next_id = 1

    @classmethod
    def for_config(cls, config, **kwargs) -> Tracker:
        """A tracker for a :class:`radar.config.RadarConfig` (bin widths, ``M//2``, frame rate).

        Examples
        --------
        >>> from radar.config import preset
        >>> round(Tracker.for_config(preset("carrada")).scale[0], 4)
        np.float64(0.1998)
        """
        return cls(1.0 / config.frame_rate_hz, range_bin_m=config.range_resolution_m,
                   velocity_bin_mps=config.velocity_resolution_mps,
                   doppler_zero_bin=config.n_chirps // 2, **kwargs)

    def measurements(self, table: np.ndarray) -> np.ndarray:
        """Range (m) and velocity (m/s) of the valid rows of a cluster table, in row order."""
        table = np.asarray(table, dtype=np.float64)
        if table.ndim != 2 or table.shape[1] != N_FEATURES or not np.isfinite(table).all():
            raise RadarConfigError(f"Tracker: a cluster table is a finite [cluster, {N_FEATURES}]"
                                   f" array (radar.clustering.FEATURES); got shape {table.shape}")
        rows = table[table[:, 0] > 0.5]
        return np.column_stack([rows[:, 1], rows[:, 2] - self.doppler_zero_bin]) * self.scale

    def update(self, table: np.ndarray) -> np.ndarray:
        """Advance one frame with this frame's cluster table; return the track table.

        Returns
        -------
        ndarray of float64, shape (max_tracks, N_STATE)
            Columns :data:`STATE`; row = track slot.
        """
        z = self.measurements(table)
        self.x = self.x @ self.F.T
        self.P = self.F @ self.P @ self.F.T + self.Q
        live = np.flatnonzero(self.alive)
        S = self.P[live] + self.R
        S_inv = np.linalg.inv(S)
        nu = z[None, :, :] - self.x[live][:, None, :]                  # [track, meas, 2]
        d2 = np.einsum("tma,tab,tmb->tm", nu, S_inv, nu)
        assigned_meas = np.zeros(len(z), dtype=bool)
        hit = np.zeros(len(self.alive), dtype=bool)
        if d2.size:
            from scipy.optimize import linear_sum_assignment

            gated = d2 <= self.gate
            rows, cols = linear_sum_assignment(np.where(gated, d2, _FORBIDDEN))
            ok = gated[rows, cols]
            t, m = live[rows[ok]], cols[ok]
            K = self.P[t] @ S_inv[rows[ok]]
            self.x[t] += np.einsum("tab,tb->ta", K, nu[rows[ok], m])
            I_K = np.eye(2) - K
            self.P[t] = I_K @ self.P[t] @ I_K.transpose(0, 2, 1) + K @ self.R @ K.transpose(0, 2, 1)
            hit[t], assigned_meas[m] = True, True
        missed = self.alive & ~hit
        self.hits += hit
        self.misses = np.where(hit, 0, self.misses + missed)
        confirmed = self.hits >= self.confirm_hits
        dead = missed & (~confirmed | (self.misses >= self.max_misses))
        self.alive &= ~dead
        self._birth(z[~assigned_meas])
        return self.table()

    def _birth(self, z: np.ndarray) -> None:
        slots = np.flatnonzero(~self.alive)[: len(z)]
        n = len(slots)
        self.x[slots], self.P[slots] = z[:n], self.R
        self.alive[slots], self.hits[slots], self.misses[slots] = True, 1, 0
        self.ids[slots] = self.next_id + np.arange(n)
        self.next_id += n

    def table(self) -> np.ndarray:
        """The current track table (see :meth:`update`)."""
        out = np.column_stack([np.ones(len(self.alive)), self.ids,
                               self.hits >= self.confirm_hits, self.x, self.hits, self.misses])
        return np.where(self.alive[:, None], out.astype(np.float64), 0.0)


def track_sequence(tables: np.ndarray, **params) -> np.ndarray:
    """Run a fresh :class:`Tracker` over a sequence of cluster tables, in order.

    Parameters
    ----------
    tables : ndarray, shape (n_frames, n_clusters, N_FEATURES)
        One cluster table per frame.
    **params
        :class:`Tracker` arguments (``dt_s`` required).

    Returns
    -------
    ndarray of float64, shape (n_frames, max_tracks, N_STATE)

    Raises
    ------
    RadarConfigError
        Bad parameters or tables.

    Examples
    --------
    >>> track_sequence(np.zeros((2, 3, 5)), dt_s=0.1, max_tracks=1).shape
    (2, 1, 7)
    """
    tables = np.asarray(tables, dtype=np.float64)
    if tables.ndim != 3:
        raise RadarConfigError(f"track_sequence: tables need shape (frames, clusters, "
                               f"{N_FEATURES}); got {tables.shape}")
    tracker = Tracker(**params)
    return np.stack([tracker.update(t) for t in tables]) if len(tables) else np.zeros(
        (0, tracker.alive.size, N_STATE))
