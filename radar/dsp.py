"""Conventional radar DSP: windows, DFTs, magnitude, dB and the range-Doppler map.

This is the golden reference the spiking lowerings are checked against, so every
function returns float64 or complex128 and the DFT is defined by one explicit
matrix (:func:`dft_matrix`) that the fast path (:func:`dft`, via ``np.fft``)
reproduces to rounding error.

Conventions
-----------
* Windows are **symmetric** (``scipy.signal.get_window(..., fftbins=False)``, the
  same coefficients as ``np.hanning``/``np.hamming``/``np.blackman``): the first
  and last taps are mirror images, ``w[l] = w[n-1-l]``.
* DFT: ``X[k] = sum_l x[l] exp(-2j*pi*k*l/n_fft)``, no scaling; ``n_fft > n_in``
  zero-pads. ``keep="positive"`` keeps bins ``0..n_fft//2-1`` (real-sampled
  radars); ``shift=True`` applies ``fftshift`` to the kept bins, so with
  ``keep="all"`` bin 0 (zero Doppler / broadside) sits at index ``n_fft//2``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import scipy.signal

from ir.errors import RadarConfigError

__all__ = [
    "WINDOW_KINDS",
    "MAGNITUDE_KINDS",
    "KEEP_MODES",
    "window_coefficients",
    "apply_window",
    "dft_bins",
    "dft_matrix",
    "dft",
    "magnitude",
    "to_db",
    "range_doppler_map",
    "angle_fft",
]

#: Our window names -> scipy's names.
_SCIPY_WINDOW: Mapping[str, str] = {
    "hann": "hann",
    "hamming": "hamming",
    "blackman": "blackman",
    "rect": "boxcar",
}
WINDOW_KINDS = tuple(_SCIPY_WINDOW)

#: Magnitude kind -> function of a complex array (the registry both public entry points use).
_MAGNITUDE: Mapping[str, Callable[[np.ndarray], np.ndarray]] = {
    "l2": np.abs,
    "l1": lambda z: np.abs(z.real) + np.abs(z.imag),
    "square": lambda z: z.real * z.real + z.imag * z.imag,
}
MAGNITUDE_KINDS = tuple(_MAGNITUDE)

KEEP_MODES = ("all", "positive")
_DB_FACTOR = {"amplitude": 20.0, "power": 10.0}


def _choice(value: object, choices: tuple[str, ...], name: str) -> str:
    if not isinstance(value, str) or value not in choices:
        raise RadarConfigError(
            f"{name}={value!r} is not a valid choice; use one of {', '.join(map(repr, choices))}"
        )
    return value


def _axis(axis: int, ndim: int, name: str) -> int:
    if isinstance(axis, bool) or not isinstance(axis, int | np.integer) or not -ndim <= axis < ndim:
        raise RadarConfigError(
            f"{name}={axis!r} is out of range for an input with {ndim} dimension(s); "
            f"use an integer in {-ndim}..{ndim - 1}"
        )
    return int(axis) % ndim


def _positive_int(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise RadarConfigError(f"{name}={value!r} must be a positive integer (>= 1)")
    return int(value)


def _as_float(x: object) -> np.ndarray:
    """float64 for real input, complex128 for complex input."""
    arr = np.asarray(x)
    return arr.astype(np.complex128 if np.iscomplexobj(arr) else np.float64, copy=False)


def window_coefficients(kind: str, n: int) -> np.ndarray:
    """The ``n`` symmetric taps of a window.

    Parameters
    ----------
    kind : {"hann", "hamming", "blackman", "rect"}
        Window family. ``"rect"`` is all ones (no window).
    n : int
        Number of taps, >= 1.

    Returns
    -------
    ndarray of float64, shape (n,)
        Symmetric coefficients, e.g. Hann ``w[l] = 0.5 - 0.5 cos(2 pi l/(n-1))``.

    Raises
    ------
    RadarConfigError
        If ``kind`` is unknown or ``n`` is not a positive integer.

    Examples
    --------
    >>> window_coefficients("hann", 5).tolist()
    [0.0, 0.5, 1.0, 0.5, 0.0]
    >>> window_coefficients("rect", 3).tolist()
    [1.0, 1.0, 1.0]

    Notes
    -----
    Symmetric (not periodic/"DFT-even") windows, as ``np.hanning`` and MATLAB's
    defaults; a length-1 window is ``[1.0]``.
    """
    name = _SCIPY_WINDOW[_choice(kind, WINDOW_KINDS, "window kind")]
    n = _positive_int(n, "window length n")
    return np.asarray(scipy.signal.get_window(name, n, fftbins=False), dtype=np.float64)


def apply_window(x: object, kind: str, axis: int = -1) -> np.ndarray:
    """Multiply ``x`` by a symmetric window along one axis.

    Parameters
    ----------
    x : array_like
        Real or complex samples.
    kind : {"hann", "hamming", "blackman", "rect"}
        Window family (see :func:`window_coefficients`).
    axis : int, default -1
        Axis along which the window runs.

    Returns
    -------
    ndarray
        ``x * w`` broadcast along ``axis``; float64 or complex128.

    Raises
    ------
    RadarConfigError
        For an unknown kind or an axis out of range.

    Examples
    --------
    >>> apply_window(np.ones((2, 3)), "hann", axis=1).tolist()
    [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    """
    arr = _as_float(x)
    ax = _axis(axis, arr.ndim, "axis")
    w = window_coefficients(kind, arr.shape[ax])
    shape = [1] * arr.ndim
    shape[ax] = w.size
    return arr * w.reshape(shape)


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


def range_doppler_map(
    adc: object,
    *,
    window: str = "hann",
    keep: str = "all",
    shift: bool = True,
    magnitude: str = "l2",
    rx_axis: int | None = 0,
    chirp_axis: int = -2,
    sample_axis: int = -1,
    sum_rx: bool = True,
) -> np.ndarray:
    """The conventional range-Doppler map of one FMCW frame.

    Parameters
    ----------
    adc : array_like
        Cube ``[rx, chirp, sample]`` (axes set by the ``*_axis`` arguments), or a
        matrix ``[chirp, sample]`` when ``rx_axis=None``.
    window : {"hann", "hamming", "blackman", "rect"}
        Window along the sample (fast-time) axis before the range DFT.
    keep : {"all", "positive"}
        Range bins to keep: ``"positive"`` for real-sampled ADCs, ``"all"`` for IQ.
    shift : bool, default True
        fftshift the Doppler bins (zero velocity at index ``n_chirps//2``).
    magnitude : {"l2", "l1", "square"}
        Magnitude applied to each complex RD cell (see :func:`magnitude`).
    rx_axis, chirp_axis, sample_axis : int
        Axes of ``adc``; ``rx_axis=None`` means there is no receiver axis. The defaults
        (0, -2, -1) read ``[rx, chirp, sample]`` cubes and ``[chirp, sample]`` matrices.
    sum_rx : bool, default True
        Sum magnitudes over receivers (non-coherent integration).

    Returns
    -------
    ndarray of float64
        ``[range, doppler]``, or ``[rx, range, doppler]`` if ``sum_rx`` is False
        and there is an rx axis.

    Raises
    ------
    RadarConfigError
        For a wrong number of dimensions, repeated or out-of-range axes, or bad kinds.

    Examples
    --------
    A target in range bin 1 moving at Doppler bin 1, 4 chirps x 4 samples:

    >>> l, m = np.arange(4), np.arange(4)[:, None]
    >>> cube = np.exp(2j * np.pi * (l + m) / 4)[None]
    >>> rd = range_doppler_map(cube, window="rect")
    >>> np.argwhere(rd > 1).tolist(), float(rd.max().round(9))
    ([[1, 3]], 16.0)

    Notes
    -----
    ``rd[r, v] = sum_rx |sum_m sum_l w[l] adc[rx, m, l] e^{-2j pi r l/L} e^{-2j pi k_v m/M}|``
    with ``k_v`` the (shifted) Doppler bin of row ``v``.
    """
    arr = _as_float(adc)
    magnitude_fn = _MAGNITUDE[_choice(magnitude, MAGNITUDE_KINDS, "magnitude kind")]
    if rx_axis is None:
        if arr.ndim != 2:
            raise RadarConfigError(
                f"adc has {arr.ndim} dimension(s) but rx_axis=None needs [chirp, sample] (2); "
                "pass rx_axis for a 3D cube"
            )
        arr, rx_axis = arr[None], 0
        chirp_axis = _axis(chirp_axis, 2, "chirp_axis") + 1
        sample_axis = _axis(sample_axis, 2, "sample_axis") + 1
        has_rx = False
    else:
        if arr.ndim != 3:
            raise RadarConfigError(
                f"adc has {arr.ndim} dimension(s) but the cube must be [rx, chirp, sample] (3); "
                "use rx_axis=None for a single-receiver [chirp, sample] matrix"
            )
        has_rx = True
    named = {"rx_axis": rx_axis, "chirp_axis": chirp_axis, "sample_axis": sample_axis}
    axes = tuple(_axis(a, 3, name) for name, a in named.items())
    if len(set(axes)) != 3:
        raise RadarConfigError(
            f"rx_axis, chirp_axis, sample_axis = {axes} must be three different axes"
        )
    cube = np.moveaxis(arr, axes, (0, 1, 2))
    range_bins = dft(apply_window(cube, window, axis=2), axis=2, keep=keep)
    rd = magnitude_fn(dft(range_bins, axis=1, shift=shift)).swapaxes(1, 2)
    if not has_rx:
        return rd[0]
    return rd.sum(axis=0) if sum_rx else rd


def angle_fft(
    x: object, axis: int = -1, *, n_fft: int | None = None, window: str = "rect"
) -> np.ndarray:
    """Angle spectrum over a (virtual) uniform linear array, broadside at the centre.

    Parameters
    ----------
    x : array_like
        Complex snapshots with the array elements along ``axis``.
    axis : int, default -1
        Element axis.
    n_fft : int, optional
        Angle bins (zero-padding), ``>=`` the number of elements; default = elements.
    window : {"hann", "hamming", "blackman", "rect"}
        Taper across the elements.

    Returns
    -------
    ndarray of complex128
        ``dft(window * x, axis, n_fft=n_fft, keep="all", shift=True)``: bin ``n_fft//2`` is
        broadside (zero spatial frequency).

    Raises
    ------
    RadarConfigError
        For a bad axis, window or ``n_fft``.

    Examples
    --------
    >>> np.abs(angle_fft(np.ones(4))).round(9).tolist()
    [0.0, 0.0, 4.0, 0.0]
    """
    arr = _as_float(x)
    ax = _axis(axis, arr.ndim, "axis")
    return dft(apply_window(arr, window, axis=ax), axis=ax, n_fft=n_fft, keep="all", shift=True)
