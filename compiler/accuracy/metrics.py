r"""Accuracy figures a radar engineer trusts, for one stage: spiking value against golden value.

A spectrum's relative RMS error is ruled by its strongest bins (1.6 % can hide 90 % of
the weak cells decoded to 0), so a *value* stage (a DFT, a magnitude, a power map) is
judged against the **noise floor estimated from the data**:

``noise`` :math:`N`
    the median of :math:`|y|` over every cell of every frame: most cells of a radar
    spectrum hold noise only, so the median is the floor and is not moved by the few
    strong returns (nor by leakage rows).
``error_db``
    the RMS error over the *noise cells* (:math:`|y| \le 4N`, the cells that set a
    CFAR's noise estimate) relative to their own RMS,
    :math:`20\log_{10}(\lVert\hat y - y\rVert / \lVert y\rVert)` there. A code whose step
    is coarser than the noise decodes it to 0 and scores 0 dB; a faithful code scores
    far below (−20 dB and less).
``lost``
    the fraction of *signal cells* (:math:`|y| > 4N`, 12 dB above the floor) whose decoded
    magnitude is more than 6 dB off (decoded 0, clipped, or flooded).

A *decision* stage (a CFAR) is judged cell by cell (``sensitivity``, ``precision``
against the conventional mask) and object by object: an **object** is a detected cell
that is a local maximum of the conventional detector's input over its 3-cell
neighbourhood along the detector's axes (as a target list is built); a conventional
object is *kept* when the spiking mask holds a detection within ±1 bin of it, and a
spiking object is *extra* when the conventional mask holds none within ±1 bin. Only
*firm* conventional objects count as ones to keep — those still detected with the
threshold raised by :data:`FIRM_MARGIN_DB` (1 dB): a cell right at the threshold flips
under any code's rounding, as it does between two runs of a real sensor.

Examples
--------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> y = rng.normal(size=4096) + 1j * rng.normal(size=4096)
>>> y[100] = 1000.0
>>> good = value_figures(y + 0.01 * rng.normal(size=4096), y)
>>> round(good.error_db), good.lost
(-43, 0.0)
>>> zeroed = np.where(np.abs(y) > 50, y, 0)           # a code that zeroes the noise
>>> round(value_figures(zeroed, y).error_db)
0
>>> m = np.zeros((1, 8, 8), bool); m[0, 2, 3] = True
>>> f = decision_figures(m, m, m.astype(float), axes=(1, 2))
>>> f.sensitivity, f.precision, f.objects, f.kept, f.extra
(1.0, 1.0, 1, 1, 0)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["FIRM_MARGIN_DB", "LOST_DB", "NOISE_FACTOR", "DecisionFigures", "ValueFigures",
           "decision_figures", "value_figures"]

#: Cells with ``|y| > NOISE_FACTOR · median|y|`` are signal cells (12 dB above the floor).
NOISE_FACTOR = 4.0

#: A signal cell decoded more than this many dB off its golden magnitude is lost.
LOST_DB = 6.0

#: A conventional detection is a firm object when it holds with the threshold this many dB
#: higher (of power; of amplitude for an amplitude input).
FIRM_MARGIN_DB = 1.0


@dataclass(frozen=True)
class ValueFigures:
    """One value stage against its golden value (see the module docstring)."""

    noise: float
    error_db: float
    signal_cells: int
    lost: float
    zero_fraction: float

    def to_dict(self) -> dict:
        """JSON-able figures."""
        return dict(self.__dict__)


@dataclass(frozen=True)
class DecisionFigures:
    """One decision stage against the conventional decisions (see the module docstring)."""

    sensitivity: float
    precision: float
    cells: int
    spiking_cells: int
    objects: int
    kept: int
    extra: int
    frames: int
    maps: int = 0

    @property
    def missed(self) -> int:
        """Conventional objects with no spiking detection within ±1 bin."""
        return self.objects - self.kept

    @property
    def extra_per_map(self) -> float:
        """Extra objects per detection map (a frame's map, or each map of a batch axis: the
        range profile of every chirp of a chirp sequence)."""
        return self.extra / max(self.maps, 1)

    def to_dict(self) -> dict:
        """JSON-able figures (with ``missed`` and ``extra_per_map``)."""
        return {**self.__dict__, "missed": self.missed, "extra_per_map": self.extra_per_map}


def value_figures(got: np.ndarray, want: np.ndarray) -> ValueFigures:
    """Noise floor, error relative to it, and lost signal cells of ``got`` against ``want``.

    Parameters
    ----------
    got, want : ndarray
        Decoded and golden values of the same shape (real or complex).

    Returns
    -------
    ValueFigures
    """
    got = np.asarray(got).ravel()
    want = np.asarray(want).ravel()
    mag = np.abs(want)
    noise = float(np.median(mag)) if mag.size else 0.0
    if not noise > 0:  # an exact-zero floor (a noiseless synthetic map): the smallest non-zero
        nz = mag[mag > 0]
        noise = float(np.median(nz)) if nz.size else 0.0
    quiet = mag <= NOISE_FACTOR * noise
    ref = float(np.linalg.norm(want[quiet])) if quiet.any() else 0.0
    err = float(np.linalg.norm((got - want)[quiet])) if quiet.any() else 0.0
    if ref > 0:
        error_db = 20 * np.log10(max(err / ref, 1e-12))
    else:
        error_db = 0.0 if err > 0 else -240.0
    signal = ~quiet
    n_signal = int(signal.sum())
    if n_signal:
        with np.errstate(divide="ignore"):
            off = np.abs(20 * np.log10(np.abs(got[signal]) / mag[signal]))
        lost = float(np.mean(~(off <= LOST_DB)))
    else:
        lost = 0.0
    zero = float(np.mean(got[mag > 0] == 0)) if (mag > 0).any() else 0.0
    return ValueFigures(noise=noise, error_db=float(error_db), signal_cells=n_signal,
                        lost=lost, zero_fraction=zero)


def _peaks(mask: np.ndarray, power: np.ndarray, axes: Sequence[int]) -> np.ndarray:
    size = [3 if a in axes else 1 for a in range(mask.ndim)]
    peak = ndimage.maximum_filter(power, size=size, mode="nearest") == power
    return mask & peak


def _near(mask: np.ndarray, axes: Sequence[int]) -> np.ndarray:
    size = [3 if a in axes else 1 for a in range(mask.ndim)]
    return ndimage.maximum_filter(mask.astype(np.uint8), size=size, mode="constant") > 0


def decision_figures(got: np.ndarray, want: np.ndarray, power: np.ndarray, *,
                     axes: Sequence[int], frames: int = 1,
                     firm: np.ndarray | None = None) -> DecisionFigures:
    """Cell- and object-level agreement of a spiking detection mask with the conventional one.

    Parameters
    ----------
    got, want : ndarray of bool
        Spiking and conventional masks (same shape).
    power : ndarray
        The conventional detector's input (objects are its local maxima among detections).
    axes : sequence of int
        The axes the detector's window spans (other axes are a batch).
    frames : int
        How many frames the arrays hold (recorded; ``extra_per_map`` divides by the maps:
        the product of the axes the window does not span, frames included).
    firm : ndarray of bool, optional
        The conventional detections that hold with a margin (e.g. with the threshold
        raised by 1 dB): only these count as objects to keep; a conventional detection
        right at the threshold flips under any code's rounding (default: every one).

    Returns
    -------
    DecisionFigures
    """
    got = np.asarray(got) != 0
    want = np.asarray(want).astype(bool)
    power = np.abs(np.asarray(power, dtype=np.float64))
    axes = tuple(int(a) % want.ndim for a in axes)
    hits = int(np.sum(got & want))
    n_want, n_got = int(want.sum()), int(got.sum())
    want_objects = _peaks(want, power, axes) & (want if firm is None else np.asarray(firm))
    got_objects = _peaks(got, power, axes)
    kept = int(np.sum(want_objects & _near(got, axes)))
    extra = int(np.sum(got_objects & ~_near(want, axes)))
    batch = [n for a, n in enumerate(want.shape) if a not in axes]
    return DecisionFigures(
        sensitivity=hits / n_want if n_want else 1.0,
        precision=hits / n_got if n_got else 1.0,
        cells=n_want, spiking_cells=n_got, objects=int(want_objects.sum()), kept=kept,
        extra=extra, frames=frames, maps=int(np.prod(batch, dtype=np.int64)))
