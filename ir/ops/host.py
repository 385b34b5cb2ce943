r"""Host-only ops after detection: ``cluster`` (DBSCAN) and ``track`` (Kalman tracker).

Both produce fixed-capacity *tables*: real ``amplitude`` values on named axes,
one row per cluster or track slot, one column per feature.  Their meaning lives in
:mod:`radar.clustering` and :mod:`radar.tracking` (their reference implementations
delegate there; a table has no calibration bound); the compiler has no spiking
motif for them, so they always run on the host.  The column layouts are defined
here, once: :data:`CLUSTER_FEATURES` and :data:`TRACK_STATE`.

Examples
--------
>>> t = TensorType(axes={"frame": 5, "doppler": 64, "range": 256}, domain="mask")
>>> table = Cluster(max_clusters=8).infer("clu", [t])
>>> table.axes
{'frame': 5, 'cluster': 8, 'feature': 5}
>>> Track(dt_s=0.1, range_bin_m=0.2, velocity_bin_mps=0.42, doppler_zero_bin=32,
...       max_tracks=4).infer("trk", [table]).axes
{'frame': 5, 'track': 4, 'state': 7}
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, NonNegativeFloat, PositiveFloat, PositiveInt

from ir.model import Name
from ir.ops.base import Op
from ir.types import TensorType
from radar.clustering import FEATURES, cluster_detections
from radar.tracking import STATE, track_sequence

__all__ = ["CLUSTER_FEATURES", "TRACK_STATE", "Cluster", "Track"]

CLUSTER_FEATURES: tuple[str, ...] = FEATURES
"""Columns of a cluster table (``feature`` axis), as the domain defines them."""

TRACK_STATE: tuple[str, ...] = STATE
"""Columns of a track table (``state`` axis), as the domain defines them."""


class Cluster(Op):
    r"""DBSCAN clusters of the detections of a map, as a table ``[cluster, feature]``.

    Detected cells :math:`(i, j)` on the map axes ``axes`` = (range-like, Doppler-like)
    are neighbours when :math:`\sqrt{(s_0 \Delta_i)^2 + (s_1 \Delta_j)^2} \le
    \varepsilon`, with :math:`\Delta` taken circularly on ``wrap`` axes; DBSCAN
    groups them (core cells have ``min_samples`` neighbours, themselves included).
    Each cluster becomes a row of :data:`CLUSTER_FEATURES`: valid = 1, the
    power-weighted centroid bins (circular mean around the peak cell on wrapped
    axes), the number of cells and the peak cell's power; rows sorted by
    descending peak power (ties: peak bins), ``max_clusters`` rows, zero padding.
    :func:`radar.clustering.cluster_detections` is the reference.

    Parameters
    ----------
    axes : (str, str), default ("range", "doppler")
        The map axes: the first is reported as ``range_bin``, the second as ``doppler_bin``.
    wrap : (bool, bool), default (false, true)
        Which map axes are circular (Doppler).
    eps_bins : float, default 1.5
        :math:`\varepsilon` in scaled bins.
    min_samples : int, default 1
        DBSCAN's core-cell count (1: connected components of the neighbour graph).
    max_clusters : int, default 16
        Rows of the table.
    axes_scale : (float, float), default (1, 1)
        :math:`(s_0, s_1)`, bins -> distance units per map axis.

    Notes
    -----
    Inputs: a ``mask`` and optionally, second, the real ``power`` or ``amplitude``
    map it was detected on (same axes; weights and peak power; without it every
    cell weighs 1).  Output: real ``amplitude`` with the mask's other axes (a
    batch, e.g. ``frame``, in order) followed by ``{"cluster": max_clusters,
    "feature": 5}``.

    Examples
    --------
    >>> mask = TensorType(axes={"doppler": 16, "range": 32}, domain="mask")
    >>> power = mask.replace(domain="power")
    >>> Cluster(max_clusters=4).infer("clu", [mask, power]).axes
    {'cluster': 4, 'feature': 5}
    """

    arity: ClassVar[int] = 1
    no_bound: ClassVar[str] = "host-only: a table of detections, not a value"
    op: Literal["cluster"] = "cluster"
    axes: tuple[Name, Name] = ("range", "doppler")
    wrap: tuple[bool, bool] = (False, True)
    eps_bins: PositiveFloat = 1.5
    min_samples: PositiveInt = 1
    max_clusters: PositiveInt = 16
    axes_scale: tuple[PositiveFloat, PositiveFloat] = (1.0, 1.0)

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        if len(inputs) not in (1, 2):
            raise self.fail(node_id, f"takes 1 input (a mask) or 2 (mask, power map), got "
                                     f"{len(inputs)}; fix 'input'/'inputs'")
        mask = inputs[0]
        if mask.domain != "mask":
            raise self.fail(node_id, f"first input must be a detection mask; its domain is "
                                     f"{mask.domain!r} (put a cfar or threshold node before it)")
        if len(inputs) == 2:
            power = inputs[1]
            self.check_value(node_id, power, ("power", "amplitude"), allow_complex=False)
            if list(power.axes.items()) != list(mask.axes.items()):  # order matters
                raise self.fail(node_id, f"the power map's axes {dict(power.axes)} differ from "
                                         f"the mask's {dict(mask.axes)}; pass the map the mask "
                                         "was detected on")
        if self.axes[0] == self.axes[1]:
            raise self.fail(node_id, f"axes {list(self.axes)} repeat an axis; name two map axes")
        for axis in self.axes:
            self.axis_index(node_id, mask, axis, field="axes entry")
        batch = {k: v for k, v in mask.axes.items() if k not in self.axes}
        clash = sorted({"cluster", "feature"} & set(batch))
        if clash:
            raise self.fail(node_id, f"batch axes {clash} clash with the table axes 'cluster', "
                                     "'feature'; rename them upstream")
        return TensorType(axes={**batch, "cluster": self.max_clusters,
                                "feature": len(CLUSTER_FEATURES)})

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        maps = [types[0].index(a) for a in self.axes]
        moved = [np.moveaxis(np.asarray(a), maps, [-2, -1]) for a in args]
        # a mask decoded from spikes may arrive as 0/1 floats (run_program's host segments)
        return cluster_detections(moved[0] != 0, moved[1] if len(moved) == 2 else None,
                                  eps_bins=self.eps_bins, min_samples=self.min_samples,
                                  max_clusters=self.max_clusters, axes_scale=self.axes_scale,
                                  wrap=self.wrap)


class Track(Op):
    r"""Tracks over frames: a constant-velocity Kalman tracker fed one cluster table per frame.

    Frame :math:`t` of the input (axis ``frame_axis``) updates the tracker in order;
    output frame :math:`t` is the track table after that update.  Measurements
    :math:`z = (\Delta_R b_r, \Delta_v (b_d - b_0))`; state :math:`(r, \dot r)` with
    :math:`F = [[1, \Delta t], [0, 1]]`, white-acceleration :math:`Q`, gated
    (:math:`d^2 \le` ``gate``) global-nearest-neighbour association, birth /
    confirmation / deletion as in :mod:`radar.tracking` (the reference,
    :func:`radar.tracking.track_sequence`).

    Parameters
    ----------
    dt_s : float
        Frame period :math:`\Delta t`, s.
    range_bin_m, velocity_bin_mps : float
        Bin widths :math:`\Delta_R`, :math:`\Delta_v`.
    doppler_zero_bin : float
        Doppler bin of zero velocity :math:`b_0` (``n_doppler // 2`` after fftshift).
    frame_axis : str, default "frame"
        The input's frame axis (processed in order).
    max_tracks : int, default 16
    gate : float, default 9.21
        :math:`\chi^2_2` gate on the squared Mahalanobis distance (99 %).
    confirm_hits, max_misses : int, default 3
    accel_std_mps2 : float, default 2.0
    range_std_m, velocity_std_mps : float, optional
        Measurement noise (default half a bin).

    Notes
    -----
    Input: a cluster table ``[frame_axis, cluster, feature=5]`` (real amplitude),
    as :class:`Cluster` makes with a frame batch axis.  Output: ``{frame_axis: T,
    "track": max_tracks, "state": 7}``, columns :data:`TRACK_STATE`.

    Examples
    --------
    >>> t = TensorType(axes={"frame": 3, "cluster": 8, "feature": 5})
    >>> Track(dt_s=0.1, range_bin_m=1, velocity_bin_mps=1, doppler_zero_bin=0).infer(
    ...     "trk", [t]).shape
    (3, 16, 7)
    """

    no_bound: ClassVar[str] = "host-only: a table of tracks, not a value"
    op: Literal["track"] = "track"
    dt_s: PositiveFloat
    range_bin_m: PositiveFloat
    velocity_bin_mps: PositiveFloat
    doppler_zero_bin: float = Field(ge=0)
    frame_axis: Name = "frame"
    max_tracks: PositiveInt = 16
    gate: PositiveFloat = 9.21
    confirm_hits: PositiveInt = 3
    max_misses: PositiveInt = 3
    accel_std_mps2: NonNegativeFloat = 2.0
    range_std_m: PositiveFloat | None = None
    velocity_std_mps: PositiveFloat | None = None

    def tracker_params(self) -> dict:
        """Keyword arguments of :class:`radar.tracking.Tracker` (everything but ``frame_axis``)."""
        return self.model_dump(exclude={"op", "frame_axis"})

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        want = (self.frame_axis, "cluster", "feature")
        if (t.names != want or t.domain != "amplitude" or t.complex
                or t.axes["feature"] != len(CLUSTER_FEATURES)):
            raise self.fail(node_id, f"input must be a cluster table with axes {list(want)} "
                                     f"(feature = {len(CLUSTER_FEATURES)}, real amplitude); got "
                                     f"{t!r}; feed a cluster node whose mask has a "
                                     f"{self.frame_axis!r} batch axis")
        return TensorType(axes={self.frame_axis: t.axes[self.frame_axis],
                                "track": self.max_tracks, "state": len(TRACK_STATE)})

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return track_sequence(args[0], **self.tracker_params())
