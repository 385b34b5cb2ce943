"""Frame sources of a sweep: the scene simulator or a folder of ``.npy`` files.

:func:`load_frames` makes the frames ``[start, stop)`` of a source (or of its
calibration set) as a :class:`FrameBatch`.  A scene frame's randomness comes
only from ``SeedSequence([seed, stream, index])`` (stream 0 scored, 1
calibration), so the same frame comes out whoever makes it, in any order.

Products of a scene frame: ``adc`` (the raw cube ``[rx, chirp, sample]``),
``rd_power`` (the rx-summed power map ``Σ_rx |X|²``, ``[range, doppler]``,
Hann range window, Doppler fftshifted) and ``rd_db`` (``10·log10`` of it).

Examples
--------
>>> from radarsnn.sweep.sections import SceneFrames
>>> src = SceneFrames(preset="carrada", scene="random", product="rd_db", seed=3)
>>> a = load_frames(src, ".", 1, 2)
>>> a.arrays[0].shape, a.indices
((256, 64), (1,))
>>> b = load_frames(src, ".", 0, 2)
>>> bool(np.array_equal(a.arrays[0], b.arrays[1]))
True
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ir.errors import RadarConfigError

__all__ = ["FrameBatch", "TARGET_CLASSES", "random_scene", "load_frames", "folder_files",
           "frame_rng"]

#: Classes of :func:`random_scene`'s targets: (mean RCS dBsm, max |radial speed| m/s).
TARGET_CLASSES = {"pedestrian": (-5.0, 2.0), "cyclist": (0.0, 6.0), "car": (10.0, 14.0)}


@dataclass(frozen=True)
class FrameBatch:
    """Frames ``indices`` of one source: the chain input per frame and what is known of it.

    Attributes
    ----------
    indices : tuple of int
        Frame indices in the source.
    arrays : list of ndarray
        One input array per frame.
    truth : list of tuple
        Per frame, the scene's :class:`radar.scene.TargetTruth` records (empty for files).
    labels : list of int or None
        Per frame, a class label when the source has labels.
    """

    indices: tuple[int, ...]
    arrays: list[np.ndarray]
    truth: list[tuple]
    labels: list[int] | None = None


def frame_rng(seed: int, stream: int, index: int) -> np.random.Generator:
    """The generator of frame ``index`` of ``stream`` (0 scored, 1 calibration).

    Examples
    --------
    >>> float(frame_rng(1, 0, 5).random()) == float(frame_rng(1, 0, 5).random())
    True
    """
    return np.random.default_rng(np.random.SeedSequence([seed, stream, index]))


def random_scene(rng: np.random.Generator):
    """A CARRADA-like scene: 1-3 random targets, Tx->Rx leakage, static clutter, noise.

    Targets are drawn from :data:`TARGET_CLASSES` (RCS ± 3 dB Gaussian, speed uniform
    within the class limit), at 3-45 m and ±40°; ``benchmarks/cfar.py`` uses it too.

    Examples
    --------
    >>> s = random_scene(np.random.default_rng(0))
    >>> 1 <= len(s.targets) <= 3, s.noise_dbfs
    (True, -80.0)
    """
    from radar.scene import Clutter, Leakage, Scene, Target

    targets = []
    for _ in range(int(rng.integers(1, 4))):
        name = str(rng.choice(list(TARGET_CLASSES)))
        rcs, vmax = TARGET_CLASSES[name]
        targets.append(Target(range_m=float(rng.uniform(3.0, 45.0)),
                              velocity_mps=float(rng.uniform(-vmax, vmax)),
                              azimuth_deg=float(rng.uniform(-40.0, 40.0)),
                              rcs_dbsm=float(rcs + rng.normal(0.0, 3.0)), name=name))
    return Scene(name="random", targets=tuple(targets),
                 leakage=(Leakage(range_m=0.05, amplitude_dbfs=-30.0, name="tx_rx_leakage"),),
                 clutter=Clutter(n_scatterers=24, amplitude_dbfs=-75.0, min_range_m=3.0,
                                 max_range_m=48.0),
                 noise_dbfs=-80.0, gain_dbfs=-20.0)


def _scene_frame(source, stream: int, index: int) -> tuple[np.ndarray, tuple]:
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame
    from radar.spectra import range_doppler_map

    cfg, rng = preset(source.preset), frame_rng(source.seed, stream, index)
    if source.scene == "random":
        scene = random_scene(rng)
    elif source.scene in SCENE_PRESETS:
        scene = SCENE_PRESETS[source.scene]()
    else:
        raise RadarConfigError(f"sweep frames: scene {source.scene!r} is unknown; use 'random' "
                               f"or one of {sorted(SCENE_PRESETS)}")
    frame = simulate_frame(cfg, scene, seed=int(rng.integers(2**31)))
    if source.product == "adc":
        return frame.adc, frame.truth
    power = range_doppler_map(frame.adc, magnitude="square", keep="all" if cfg.iq else "positive")
    return (10.0 * np.log10(power) if source.product == "rd_db" else power), frame.truth


def folder_files(source, base_dir: str | Path) -> tuple[list[Path], list[Path]]:
    """``(scored, calibration)`` files of a folder source, sorted by name.

    Raises
    ------
    RadarConfigError
        The folder is missing or holds fewer files than the calibration needs, the
        pattern cannot be matched, or a match is not a regular file (a FIFO named
        ``f3.npy`` would block its reader forever).
    """
    folder = Path(base_dir) / source.path
    if not folder.is_dir():
        raise RadarConfigError(f"sweep frames: folder {str(folder)!r} does not exist")
    labels = None if source.labels is None else (Path(base_dir) / source.labels).resolve()
    try:  # the pattern is checked by FolderFrames; this is for one built without validation
        found = sorted(folder.glob(source.pattern))
    except (ValueError, NotImplementedError, OSError, IndexError) as err:
        raise RadarConfigError(f"sweep frames: pattern {source.pattern[:80]!r} cannot be matched "
                               f"in {str(folder)!r} ({err}); give a relative glob such as "
                               "'*.npy'") from None
    files = [f for f in found if f.resolve() != labels]
    odd = next((f for f in files if not f.is_file()), None)  # a FIFO would block its reader
    if odd is not None:
        raise RadarConfigError(f"sweep frames: {str(odd)!r} matches {source.pattern!r} but is "
                               "not a regular file (a folder, FIFO, device or socket); move it "
                               "or narrow the pattern")
    n_cal = source.calibration_frames
    if len(files) <= n_cal:
        raise RadarConfigError(f"sweep frames: folder {str(folder)!r} has {len(files)} "
                               f"{source.pattern!r} files but calibration takes the last {n_cal}"
                               "; add files or lower `calibration_frames`")
    scored = files[:-n_cal]
    if source.n_frames is not None:
        if source.n_frames > len(scored):
            raise RadarConfigError(f"sweep frames: n_frames = {source.n_frames} but folder "
                                   f"{str(folder)!r} has {len(scored)} files besides the "
                                   f"{n_cal} calibration files")
        scored = scored[:source.n_frames]
    return scored, files[-n_cal:]


def _load_npy(path: Path) -> np.ndarray:
    """One frame file, by the bounded reader: its header checked before numpy allocates."""
    from radar.readers import read_npy_array

    return read_npy_array(path, what=f"sweep frame {str(path)!r}")


def _labels(path: Path, n_scored: int, name: str) -> np.ndarray:
    """The integer class per scored file of the labels file ``path``."""
    table = _load_npy(path).ravel()
    integral = table.dtype.kind in "iu" or (
        table.dtype.kind == "f" and bool(np.all(np.isfinite(table) & (table == np.round(table)))))
    if not integral:
        raise RadarConfigError(f"sweep frames: labels {name!r} hold {table.dtype} values; give "
                               "one integer class per file")
    if table.size < n_scored:
        raise RadarConfigError(f"sweep frames: labels {name!r} hold {table.size} "
                               f"entries for {n_scored} scored files")
    return table.astype(np.int64)


def load_frames(source, base_dir: str | Path, start: int, stop: int,
                calibration: bool = False) -> FrameBatch:
    """Frames ``[start, stop)`` of ``source`` (its calibration set if ``calibration``).

    Parameters
    ----------
    source : SceneFrames or FolderFrames
        The spec's ``frames``.
    base_dir : str or Path
        Folder a relative ``path`` / ``labels`` is read from.
    start, stop : int
        Frame indices.
    calibration : bool
        Take the calibration frames instead of the scored ones.

    Returns
    -------
    FrameBatch

    Raises
    ------
    RadarConfigError
        An unknown scene, a missing folder or an unreadable file (each file read by
        :func:`radar.readers.read_npy_array`: regular files only, the header checked
        against 4 GiB and the file's size before numpy allocates).
    """
    indices = tuple(range(start, stop))
    if source.source == "scene":
        made = [_scene_frame(source, int(calibration), i) for i in indices]
        return FrameBatch(indices, [a for a, _ in made], [t for _, t in made])
    scored, cal = folder_files(source, base_dir)
    files = (cal if calibration else scored)[start:stop]
    labels = None
    if source.labels is not None and not calibration:
        table = _labels(Path(base_dir) / source.labels, len(scored), source.labels)
        labels = [int(table[i]) for i in indices]
    return FrameBatch(indices, [_load_npy(f) for f in files], [() for _ in files], labels)
