"""Detections → peaks → targets: how the demo scores a detection mask against ground truth.

A detection mask is reduced to *peaks* (detected cells that are local maxima
of the power map over their 3 × 3 neighbourhood, Doppler circular); each
ground-truth target is matched to the nearest peak within ± 1 bin in range and
in circular Doppler.  Unmatched peaks in the zero-Doppler column are static
clutter (the scenes include static scatterers and Tx→Rx leakage); the others
are false alarms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["PeakScore", "detection_peaks", "match_peak", "score_peaks"]


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


def score_peaks(mask: np.ndarray, power: np.ndarray, truth_bins: list[tuple[int, int]]
                ) -> PeakScore:
    """Peaks of ``mask`` matched to ``truth_bins``; the rest split into clutter and false alarms.

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
    n_clutter = sum(1 for p in unmatched if p[1] == zero_doppler)
    return PeakScore(found=found, n_peaks=len(peaks), n_clutter=n_clutter,
                     n_false=len(unmatched) - n_clutter)
