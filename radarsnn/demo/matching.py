"""Detections → peaks → targets: how the demo scores a detection mask against ground truth.

A detection mask is reduced to *peaks* (detected cells that are local maxima
of the power map over their 3 × 3 neighbourhood, Doppler circular); each
ground-truth target is matched to the nearest peak within ± 1 bin in range and
in circular Doppler.  Unmatched peaks in the zero-Doppler column are static
clutter (the scenes include static scatterers and Tx→Rx leakage); the others
are false alarms.  Chains without a Doppler DFT (range profiles per chirp) are scored
by :func:`score_range_peaks`, peaks along range in each chirp.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["PeakScore", "ProfileScore", "detection_peaks", "match_peak", "range_peak_hits",
           "score_peaks", "score_range_peaks"]


def detection_peaks(mask: np.ndarray, power: np.ndarray) -> np.ndarray:
    """Detected cells that are local maxima of ``power`` over their 3 × 3 neighbourhood.

    The map is ``[range, doppler]``; the Doppler axis is circular, the range
    axis is not.  Grouping by local maxima (rather than one peak per connected
    cluster) keeps a close target apart from the leakage skirt it touches.

    Returns
    -------
    ndarray of int, shape (n_peaks, 2)
        ``(range_bin, doppler_bin)`` rows in row-major order.

    Examples
    --------
    >>> m = np.zeros((5, 5), bool); m[0:3, 1] = True; m[4, 4] = True
    >>> p = np.zeros((5, 5)); p[0:3, 1] = [9.0, 5.0, 7.0]; p[4, 4] = 1.0
    >>> detection_peaks(m, p).tolist()
    [[0, 1], [2, 1], [4, 4]]
    """
    peak = ndimage.maximum_filter(power, size=3, mode=("nearest", "wrap")) == power
    return np.argwhere(mask & peak).astype(np.int64)


def match_peak(peaks: np.ndarray, r: int, d: int, n_doppler: int) -> tuple[int, int] | None:
    """The peak nearest to bin ``(r, d)`` within ± 1 bin (Doppler circular), or None.

    Examples
    --------
    >>> match_peak(np.array([[3, 0], [9, 9]]), 4, 15, 16)
    (3, 0)
    """
    if len(peaks) == 0:
        return None
    dr = np.abs(peaks[:, 0] - r)
    dd = np.abs(peaks[:, 1] - d)
    dd = np.minimum(dd, n_doppler - dd)
    near = np.flatnonzero((dr <= 1) & (dd <= 1))
    if near.size == 0:
        return None
    best = near[np.argmin(dr[near] + dd[near])]
    return int(peaks[best, 0]), int(peaks[best, 1])


@dataclass(frozen=True)
class PeakScore:
    """How one detection mask's peaks match the ground truth."""

    found: list[tuple[int, int] | None]
    n_peaks: int
    n_clutter: int
    n_false: int

    @property
    def n_found(self) -> int:
        """Targets with a peak within ± 1 bin."""
        return sum(f is not None for f in self.found)


def score_peaks(mask: np.ndarray, power: np.ndarray, truth_bins: list[tuple[int, int]], *,
                static_range_bins: int = 0) -> PeakScore:
    """Peaks of ``mask`` matched to ``truth_bins``; the rest split into clutter and false alarms.

    Unmatched peaks in the zero-Doppler column, or below range bin ``static_range_bins``
    (the near-range leakage and its chirp-to-chirp skirt; 0: none), are clutter.

    Examples
    --------
    >>> m = np.zeros((8, 8), bool); m[2, 3] = m[5, 4] = m[6, 1] = True
    >>> s = score_peaks(m, m.astype(float), [(2, 3), (7, 7)])
    >>> s.found, s.n_peaks, s.n_clutter, s.n_false
    ([(2, 3), None], 3, 1, 1)
    """
    peaks = detection_peaks(mask, power)
    found = [match_peak(peaks, r, d, mask.shape[1]) for r, d in truth_bins]
    matched = {f for f in found if f is not None}
    unmatched = [p for p in map(tuple, peaks.tolist()) if p not in matched]
    zero_doppler = mask.shape[1] // 2
    n_clutter = sum(1 for p in unmatched if p[1] == zero_doppler or p[0] < static_range_bins)
    return PeakScore(found=found, n_peaks=len(peaks), n_clutter=n_clutter,
                     n_false=len(unmatched) - n_clutter)


@dataclass(frozen=True)
class ProfileScore:
    """How the peaks of per-chirp range profiles match targets that move between chirps."""

    hits: list[int]
    n_chirps: int
    n_peaks: int
    n_static: int
    n_false: int

    @property
    def hit_rate(self) -> float:
        """Fraction of (target, chirp) pairs with a peak within ± 1 bin."""
        return sum(self.hits) / (len(self.hits) * self.n_chirps) if self.hits else 0.0


def score_range_peaks(mask: np.ndarray, power: np.ndarray, truth_bins: list[np.ndarray], *,
                      static_bins: int = 3) -> ProfileScore:
    """Peaks of a ``[chirp, range]`` mask matched, chirp by chirp, to each target's bin.

    A peak is a detected cell that is a local maximum of ``power`` over its 3 range
    neighbours.  Target ``i`` is hit on chirp ``m`` when a peak lies within ± 1 bin of
    ``round(truth_bins[i][m])``.  Unmatched peaks below range bin ``static_bins`` are the
    near-range leakage (static); the others are false alarms.

    Examples
    --------
    >>> m = np.zeros((2, 10), bool); m[0, 4] = m[1, 5] = m[1, 1] = m[1, 8] = True
    >>> s = score_range_peaks(m, m.astype(float), [np.array([4.2, 6.4])])
    >>> s.hits, s.n_peaks, s.n_static, s.n_false, s.hit_rate
    ([2], 4, 1, 1, 1.0)
    """
    hit, matched, rows, cols = _range_matches(mask, power, truth_bins)
    hits = [int(h.sum()) for h in hit]
    n_static = int(np.count_nonzero(~matched & (cols < static_bins)))
    return ProfileScore(hits=hits, n_chirps=int(mask.shape[0]), n_peaks=int(rows.size),
                        n_static=n_static, n_false=int(np.count_nonzero(~matched)) - n_static)


def range_peak_hits(mask: np.ndarray, power: np.ndarray,
                    truth_bins: list[np.ndarray]) -> np.ndarray:
    """``hits[i, m]``: target ``i`` is hit on chirp ``m`` (as :func:`score_range_peaks`).

    Examples
    --------
    >>> m = np.zeros((2, 10), bool); m[0, 4] = True
    >>> range_peak_hits(m, m.astype(float), [np.array([4.2, 6.4])]).tolist()
    [[True, False]]
    """
    return _range_matches(mask, power, truth_bins)[0]


def _range_matches(mask, power, truth_bins):
    """Per target and chirp whether a peak is within ± 1 bin; which peaks matched; the
    peaks' rows and columns."""
    peak = ndimage.maximum_filter1d(power, size=3, axis=1, mode="nearest") == power
    rows, cols = np.nonzero(mask & peak)
    matched = np.zeros(rows.size, bool)
    hit = np.zeros((len(truth_bins), mask.shape[0]), bool)
    for i, bins in enumerate(truth_bins):
        want = np.rint(np.asarray(bins))[rows]
        near = np.abs(cols - want) <= 1
        matched |= near
        hit[i, rows[near]] = True
    return hit, matched, rows, cols
