"""Conventional radar DSP: DFTs, magnitude and dB.

This is the golden reference the spiking lowerings are checked against, so every
function returns float64 or complex128 and the DFT is defined by one explicit
matrix (:func:`dft_matrix`) that the fast path (:func:`dft`, via ``np.fft``)
reproduces to rounding error.

Conventions
-----------
* DFT: ``X[k] = sum_l x[l] exp(-2j*pi*k*l/n_fft)``, no scaling; ``n_fft > n_in``
  zero-pads. ``keep="positive"`` keeps bins ``0..n_fft//2-1`` (real-sampled
  radars); ``shift=True`` applies ``fftshift`` to the kept bins, so with
  ``keep="all"`` bin 0 (zero Doppler / broadside) sits at index ``n_fft//2``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ir.errors import RadarConfigError
from radar._checks import _as_float, _axis, _choice, _positive_int

__all__ = [
    "MAGNITUDE_KINDS",
    "KEEP_MODES",
    "dft_bins",
    "dft_matrix",
    "dft",
    "magnitude",
    "to_db",
]

#: Magnitude kind -> function of a complex array (used by magnitude and radar.spectra).
_MAGNITUDE: Mapping[str, Callable[[np.ndarray], np.ndarray]] = {
    "l2": np.abs,
    "l1": lambda z: np.abs(z.real) + np.abs(z.imag),
    "square": lambda z: z.real * z.real + z.imag * z.imag,
}
MAGNITUDE_KINDS = tuple(_MAGNITUDE)

KEEP_MODES = ("all", "positive")
_DB_FACTOR = {"amplitude": 20.0, "power": 10.0}


def _n_fft(n_in: int, n_fft: int | None) -> int:
    if n_fft is None:
        return n_in
    n_fft = _positive_int(n_fft, "n_fft")
    if n_fft < n_in:
        raise RadarConfigError(
            f"n_fft={n_fft} is smaller than the input length {n_in}; the DFT only zero-pads, "
            f"it never truncates: use n_fft >= {n_in} or crop the input first"
        )
    return n_fft


def dft_bins(n_fft: int, *, keep: str = "all", shift: bool = False) -> np.ndarray:
    """The DFT bin index ``k`` of each output row, in output order.

    Parameters
    ----------
    n_fft : int
        DFT length.
    keep : {"all", "positive"}
        ``"all"`` keeps bins ``0..n_fft-1``; ``"positive"`` keeps ``0..n_fft//2-1``.
    shift : bool
        Apply ``np.fft.fftshift`` to the kept bins (meant for ``keep="all"``).

    Returns
    -------
    ndarray of int64
        Bin indices; row ``i`` of :func:`dft_matrix` is DFT bin ``dft_bins(...)[i]``.

    Raises
    ------
    RadarConfigError
        For a bad ``n_fft`` or ``keep``.

    Examples
    --------
    >>> dft_bins(4, shift=True).tolist()
    [2, 3, 0, 1]
    >>> dft_bins(8, keep="positive").tolist()
    [0, 1, 2, 3]
    """
    n_fft = _positive_int(n_fft, "n_fft")
    n_kept = n_fft if _choice(keep, KEEP_MODES, "keep") == "all" else n_fft // 2
    if n_kept == 0:
        raise RadarConfigError(f"keep='positive' with n_fft={n_fft} keeps no bins; use n_fft >= 2")
    bins = np.arange(n_kept, dtype=np.int64)
    return np.fft.fftshift(bins) if shift else bins


def dft_matrix(
    n_in: int, *, n_fft: int | None = None, keep: str = "all", shift: bool = False
) -> np.ndarray:
    """The exact DFT matrix, one row per kept output bin.

    Parameters
    ----------
    n_in : int
        Input length (columns).
    n_fft : int, optional
        DFT length, ``>= n_in`` (default ``n_in``); larger means zero-padding.
    keep : {"all", "positive"}
        Which bins to keep (see :func:`dft_bins`).
    shift : bool
        fftshift the kept bins.

    Returns
    -------
    ndarray of complex128, shape (K, n_in)
        ``W[i, l] = exp(-2j*pi*k_i*l/n_fft)`` with ``k_i = dft_bins(...)[i]``, so
        ``W @ x`` is the DFT of ``x`` zero-padded to ``n_fft``.

    Raises
    ------
    RadarConfigError
        If ``n_fft < n_in`` or a parameter is invalid.

    Examples
    --------
    >>> (dft_matrix(4).round(12) + 0).tolist()[1]
    [(1+0j), -1j, (-1+0j), 1j]
    >>> dft_matrix(3, n_fft=4, keep="positive").shape
    (2, 3)

    Notes
    -----
    The phase index ``k*l mod n_fft`` is formed in integers before the complex
    exponential, so large ``k*l`` loses no precision.
    """
    n_in = _positive_int(n_in, "n_in")
    n = _n_fft(n_in, n_fft)
    bins = dft_bins(n, keep=keep, shift=shift)
    phase_index = np.outer(bins, np.arange(n_in, dtype=np.int64)) % n
    return np.exp((-2j * np.pi / n) * phase_index)


def dft(
    x: object,
    axis: int = -1,
    *,
    n_fft: int | None = None,
    keep: str = "all",
    shift: bool = False,
) -> np.ndarray:
    """DFT along one axis via ``np.fft``, equal to :func:`dft_matrix` applied along it.

    Parameters
    ----------
    x : array_like
        Real or complex samples.
    axis : int, default -1
        Axis to transform; it becomes the bin axis (same position).
    n_fft, keep, shift
        As in :func:`dft_matrix`.

    Returns
    -------
    ndarray of complex128
        ``X[..., i, ...] = sum_l x[..., l, ...] exp(-2j*pi*k_i*l/n_fft)``.

    Raises
    ------
    RadarConfigError
        For a bad axis, ``n_fft < len``, or bad ``keep``.

    Examples
    --------
    >>> dft([1.0, 2.0, 3.0, 4.0]).real.tolist()
    [10.0, -2.0, -2.0, -2.0]
    >>> dft([1.0, 0.0, 0.0, 0.0], n_fft=8, keep="positive").real.tolist()
    [1.0, 1.0, 1.0, 1.0]

    Notes
    -----
    Real input with ``keep="positive"`` uses ``np.fft.rfft`` (same bins, half the work).
    """
    arr = _as_float(x)
    ax = _axis(axis, arr.ndim, "axis")
    n_in = _positive_int(arr.shape[ax], f"length of axis {ax}")
    n = _n_fft(n_in, n_fft)
    bins = dft_bins(n, keep=keep, shift=shift)
    if keep == "positive" and not np.iscomplexobj(arr):
        spectrum = np.fft.rfft(arr, n=n, axis=ax)
    else:
        spectrum = np.fft.fft(arr, n=n, axis=ax)
    if keep == "all" and not shift:
        return spectrum
    return np.take(spectrum, bins, axis=ax)


def magnitude(x: object, kind: str = "l2") -> np.ndarray:
    """Magnitude of complex values.

    Parameters
    ----------
    x : array_like
        Complex (or real) values.
    kind : {"l2", "l1", "square"}
        ``l2 = |x| = sqrt(Re^2 + Im^2)``, ``l1 = |Re| + |Im|``, ``square = Re^2 + Im^2``.

    Returns
    -------
    ndarray of float64

    Raises
    ------
    RadarConfigError
        For an unknown kind.

    Examples
    --------
    >>> [magnitude(3 - 4j, k).item() for k in ("l2", "l1", "square")]
    [5.0, 7.0, 25.0]
    """
    fn = _MAGNITUDE[_choice(kind, MAGNITUDE_KINDS, "magnitude kind")]
    return np.asarray(fn(np.asarray(x, dtype=np.complex128)), dtype=np.float64)


def to_db(x: object, *, domain: str = "amplitude", floor_db: float = -300.0) -> np.ndarray:
    """Decibels with a floor, never ``-inf``.

    Parameters
    ----------
    x : array_like
        Amplitudes (``domain="amplitude"``; complex allowed, ``|x|`` is used) or
        non-negative real powers (``domain="power"``).
    domain : {"amplitude", "power"}
        ``20*log10(|x|)`` or ``10*log10(x)``.
    floor_db : float, default -300.0
        Lower bound of the result (zeros map to it).

    Returns
    -------
    ndarray of float64
        ``max(factor*log10(x), floor_db)``.

    Raises
    ------
    RadarConfigError
        For an unknown domain, a non-finite floor, or complex/negative powers.

    Examples
    --------
    >>> to_db([10.0, 1.0, 0.0]).tolist()
    [20.0, 0.0, -300.0]
    >>> to_db([100.0], domain="power").tolist()
    [20.0]
    """
    factor = _DB_FACTOR[_choice(domain, tuple(_DB_FACTOR), "domain")]
    if not np.isfinite(floor_db):
        raise RadarConfigError(f"floor_db={floor_db!r} must be a finite number of dB, e.g. -300")
    arr = np.asarray(x)
    if domain == "power":
        if np.iscomplexobj(arr):
            raise RadarConfigError(
                "to_db: domain='power' needs real powers but got complex values; "
                "pass magnitude(x, 'square') or use domain='amplitude'"
            )
        arr = arr.astype(np.float64, copy=False)
        if np.any(arr < 0):
            raise RadarConfigError(
                f"to_db: domain='power' got negative values (min {arr.min():.6g}); "
                "powers must be >= 0"
            )
    else:
        arr = np.abs(arr).astype(np.float64, copy=False)
    with np.errstate(divide="ignore"):
        return np.maximum(factor * np.log10(arr), float(floor_db))
