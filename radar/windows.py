"""Symmetric tapering windows for the conventional DSP reference.

Windows are **symmetric** (``scipy.signal.get_window(..., fftbins=False)``, the same
coefficients as ``np.hanning``/``np.hamming``/``np.blackman``): the first and last
taps are mirror images, ``w[l] = w[n-1-l]``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import scipy.signal

from radar._checks import _as_float, _axis, _choice, _positive_int

__all__ = ["WINDOW_KINDS", "window_coefficients", "apply_window"]

#: Our window names -> scipy's names.
_SCIPY_WINDOW: Mapping[str, str] = {
    "hann": "hann",
    "hamming": "hamming",
    "blackman": "blackman",
    "rect": "boxcar",
}
WINDOW_KINDS = tuple(_SCIPY_WINDOW)


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
