r"""Region-of-interest (ROI) sequences of classed objects in range-Doppler maps: a seeded dataset.

Each *scene* holds 1-3 objects (car, pedestrian, cyclist; :mod:`radar.signatures`) plus
static clutter, seen for ``n_frames`` frames at the sensor's frame rate. Every frame's
range-Doppler power map is synthesised directly (:func:`synthesize_rd`), turned into dB
above its median (:func:`db_above_noise`, the noise floor), and an ROI of
``roi_shape = (range, doppler)`` bins is cut around each object's body
(:func:`extract_rois`, centre jittered by up to ``jitter_bins`` to mimic detection
offsets). One object's ROIs over the frames form one sample ``(frame, range, doppler)``
labelled with its class. Scenes are split into train/validation/test by a per-scene
draw, so the objects of one scene never straddle splits.

The map synthesis (its formulas and what it leaves out) is in :mod:`radar.rd_synthesis`;
this module re-exports its functions.

Examples
--------
>>> ds = make_dataset(4, seed=0, roi_shape=(16, 16), n_frames=2)
>>> ds.x.shape[1:], ds.x.dtype, sorted(set(ds.split.tolist())) <= ["test", "train", "val"]
((2, 16, 16), dtype('float32'), True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ir.errors import RadarConfigError
from radar.config import RadarConfig, preset
from radar.rd_synthesis import db_above_noise, noise_floor, point_bins, synthesize_rd
from radar.signatures import CLASSES, ObjectState, Scatterers, random_object, scatterers

__all__ = [
    "RoiDataset",
    "db_above_noise",
    "extract_rois",
    "make_dataset",
    "noise_floor",
    "point_bins",
    "synthesize_rd",
]


@dataclass(frozen=True, eq=False)
class RoiDataset:
    """ROI sequences with labels and provenance (one row per object of a scene).

    Attributes
    ----------
    x : ndarray of float32, shape (n, frame, range, doppler)
        dB above the frame's noise floor.
    y : ndarray of int64, shape (n,)
        Class labels, ``CLASSES[y]``.
    split : ndarray of str, shape (n,)
        ``"train"``, ``"val"`` or ``"test"``.
    meta : dict of str to ndarray
        Per sample: ``scene``, ``range_m``, ``velocity_mps`` (radial), ``azimuth_deg``,
        ``rcs_dbsm``, ``noise_dbfs``, ``peak_db`` (ROI maximum), ``n_objects``.
    classes : tuple of str
        Class names.
    """

    x: np.ndarray
    y: np.ndarray
    split: np.ndarray
    meta: dict[str, np.ndarray]
    classes: tuple[str, ...] = CLASSES

    def subset(self, split: str) -> RoiDataset:
        """The samples of one split.

        Examples
        --------
        >>> ds = make_dataset(6, seed=1, roi_shape=(8, 8), n_frames=1)
        >>> ds.subset("train").x.shape[0] + ds.subset("val").x.shape[0] \\
        ...     + ds.subset("test").x.shape[0] == ds.x.shape[0]
        True
        """
        keep = self.split == split
        return RoiDataset(self.x[keep], self.y[keep], self.split[keep],
                          {k: v[keep] for k, v in self.meta.items()}, self.classes)


def extract_rois(maps: np.ndarray, centers: np.ndarray, roi_shape: tuple[int, int],
                 fill: float = 0.0) -> np.ndarray:
    """Cut ROIs ``(range, doppler)`` out of maps ``[..., doppler, range]`` around centres.

    Parameters
    ----------
    maps : ndarray, shape (frame, doppler, range)
        One map per frame.
    centers : ndarray of int, shape (object, frame, 2)
        ``(range_bin, doppler_bin)`` of each object in each frame.
    roi_shape : (int, int)
        ROI size ``(range, doppler)``; the centre is at index ``size // 2``.
    fill : float
        Value of cells beyond the range axis (Doppler wraps around).

    Returns
    -------
    ndarray, shape (object, frame, range, doppler)

    Examples
    --------
    >>> maps = np.arange(12.0).reshape(1, 3, 4)  # 3 Doppler x 4 range bins
    >>> extract_rois(maps, np.array([[[0, 0]]]), (2, 3))[0, 0].tolist()
    [[0.0, 0.0, 0.0], [8.0, 0.0, 4.0]]
    """
    maps = np.asarray(maps)
    centers = np.asarray(centers, dtype=np.int64)
    n_dop, n_rng = maps.shape[-2:]
    size_r, size_d = roi_shape
    r_idx = centers[..., 0, None] - size_r // 2 + np.arange(size_r)  # (o, f, R)
    d_idx = (centers[..., 1, None] - size_d // 2 + np.arange(size_d)) % n_dop  # (o, f, D)
    inside = (r_idx >= 0) & (r_idx < n_rng)
    frame = np.arange(maps.shape[0])[None, :, None, None]
    out = maps[frame, d_idx[:, :, None, :], np.clip(r_idx, 0, n_rng - 1)[..., None]]
    return np.where(inside[..., None], out, fill)


def _place(obj: ObjectState, duration_s: float, rng: np.random.Generator,
           limits_m: tuple[float, float]) -> ObjectState:
    """Move the object's start so its whole track stays inside ``limits_m``."""
    travel = obj.radial_velocity_mps * duration_s
    lo, hi = limits_m[0] + max(0.0, -travel), limits_m[1] - max(0.0, travel)
    return obj.model_copy(update={"range_m": float(rng.uniform(lo, hi))})


def make_dataset(n_scenes: int, *, seed: int, roi_shape: tuple[int, int] = (32, 32),
                 n_frames: int = 8, config: RadarConfig | None = None,
                 split_fractions: tuple[float, float] = (0.7, 0.15),
                 max_objects: int = 3, jitter_bins: int = 1,
                 noise_dbfs: tuple[float, float] = (-80.0, -64.0),
                 clutter_points: int = 16) -> RoiDataset:
    """A seeded dataset of ROI sequences (see the module docstring).

    Parameters
    ----------
    n_scenes : int
        Scenes to simulate; each gives 1..``max_objects`` samples.
    seed : int
        Scene ``i`` draws from ``numpy.random.default_rng([seed, i])``, so a scene does not
        depend on how many are made.
    roi_shape : (int, int)
        ROI size ``(range, doppler)`` in bins.
    n_frames : int
        Frames per sequence (one per ``1 / config.frame_rate_hz``).
    config : RadarConfig, optional
        The sensor (default ``preset("carrada")``).
    split_fractions : (float, float)
        Train and validation fractions of the scenes; the rest is the test split.
    max_objects : int
        Objects per scene, drawn uniformly from 1..max_objects, classes uniformly.
    jitter_bins : int
        Per-frame ROI centre offset, uniform in ``-jitter_bins..jitter_bins`` per axis.
    noise_dbfs : (float, float)
        Range of the per-scene thermal noise (rms per rail, dBFS) — sets the SNR spread.
    clutter_points : int
        Static clutter points per scene (-10..5 dBsm, 2..50 m, zero Doppler).

    Returns
    -------
    RoiDataset

    Raises
    ------
    RadarConfigError
        For ``n_scenes < 1``, ``n_frames < 1``, an ROI larger than the map, or fractions
        outside ``[0, 1]`` summing above 1.

    Notes
    -----
    The ROIs are synthesised on their own bins only and referred to the analytic noise floor
    :func:`noise_floor` (the expected median of the whole map, which
    :func:`db_above_noise` uses on full maps; they agree within a fraction of a dB).
    Cost: about 2 ms per ROI frame; see docs/classifier.md for measured times.
    """
    config = config or preset("carrada")
    if n_scenes < 1 or n_frames < 1:
        raise RadarConfigError(f"make_dataset: n_scenes = {n_scenes} and n_frames = {n_frames} "
                               "must be >= 1")
    if not (0 < roi_shape[0] <= config.n_range_bins and 0 < roi_shape[1] <= config.n_chirps):
        raise RadarConfigError(f"make_dataset: roi_shape {tuple(roi_shape)} must fit the map "
                               f"({config.n_range_bins} range x {config.n_chirps} Doppler bins)")
    f_train, f_val = split_fractions
    if min(f_train, f_val) < 0 or f_train + f_val > 1:
        raise RadarConfigError(f"make_dataset: split_fractions {split_fractions} must be >= 0 "
                               "and sum to at most 1")
    dt = 1.0 / config.frame_rate_hz
    limits = (3.0, min(48.0, 0.95 * config.max_range_m))
    xs, rows = [], []
    for scene in range(n_scenes):
        rng = np.random.default_rng([seed, scene])
        u = rng.random()
        split = "train" if u < f_train else "val" if u < f_train + f_val else "test"
        kinds = rng.integers(0, len(CLASSES), rng.integers(1, max_objects + 1))
        objs = [_place(random_object(CLASSES[k], rng), (n_frames - 1) * dt, rng, limits)
                for k in kinds]
        noise = rng.uniform(*noise_dbfs)
        clutter = Scatterers(rng.uniform(2.0, limits[1], clutter_points),
                             np.zeros(clutter_points), rng.uniform(-60, 60, clutter_points),
                             rng.uniform(-10.0, 5.0, clutter_points))
        floor = noise_floor(config, noise)
        rois = np.zeros((len(objs), n_frames, *roi_shape))
        for f in range(n_frames):
            pts = Scatterers.concat([clutter, *(scatterers(o, f * dt) for o in objs)])
            ref_r = np.array([o.range_m + o.radial_velocity_mps * f * dt for o in objs])
            ref_v = np.array([o.radial_velocity_mps for o in objs])
            r_bin, d_bin = point_bins(config, ref_r, ref_v)
            jitter = rng.integers(-jitter_bins, jitter_bins + 1, (len(objs), 2))
            centers = np.stack([np.rint(r_bin), np.rint(d_bin)], axis=1).astype(int) + jitter
            for i, (c_r, c_d) in enumerate(centers):
                r_idx = c_r - roi_shape[0] // 2 + np.arange(roi_shape[0])
                d_idx = (c_d - roi_shape[1] // 2 + np.arange(roi_shape[1])) % config.n_chirps
                inside = (r_idx >= 0) & (r_idx < config.n_range_bins)
                power = synthesize_rd(config, pts, rng, noise_dbfs=noise, range_bins=r_idx,
                                      doppler_bins=d_idx)
                roi_db = 10 * np.log10(np.maximum(power, 1e-300) / floor).T
                rois[i, f] = np.where(inside[:, None], roi_db, 0.0)
        xs.append(rois.astype(np.float32))
        for i, o in enumerate(objs):
            rows.append((int(kinds[i]), split, scene, o.range_m, o.radial_velocity_mps,
                         o.azimuth_deg, o.rcs_dbsm, noise, float(rois[i].max()), len(objs)))
    cols = list(zip(*rows, strict=True))
    names = ("scene", "range_m", "velocity_mps", "azimuth_deg", "rcs_dbsm", "noise_dbfs",
             "peak_db", "n_objects")
    meta = {name: np.asarray(col) for name, col in zip(names, cols[2:], strict=True)}
    return RoiDataset(x=np.concatenate(xs), y=np.asarray(cols[0], dtype=np.int64),
                      split=np.asarray(cols[1]), meta=meta)
