"""Chain-level spectra of the conventional DSP reference: range-Doppler map and angle FFT.

Both are compositions of :mod:`radar.windows` and :mod:`radar.dsp` (window, DFT,
magnitude) with the DFT conventions documented there.
"""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError
from radar._checks import _as_float, _axis, _choice
from radar.dsp import _MAGNITUDE, MAGNITUDE_KINDS, dft
from radar.windows import apply_window

__all__ = ["range_doppler_map", "angle_fft"]


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
