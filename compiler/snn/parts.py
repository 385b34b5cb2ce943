"""Signed and complex values on a trailing ``part`` axis, and per-input normalisation.

Part layouts (:data:`PartLayout`, an encoder's ``split`` and a decoder's
``combine``) put signed or complex values on a trailing ``part`` axis:
``re_im`` → (Re, Im); ``signed`` → (relu(x), relu(−x)); ``re_im_signed`` →
(relu Re, relu −Re, relu Im, relu −Im); ``none`` adds no axis.
:func:`split_values` spreads values over the parts, :func:`combine_parts`
folds them back.

Per-input normalisation (``Encoder.normalize_axes``): before the parts are
formed, each slice over those axes is divided by its largest
``max(|Re x|, |Im x|)`` (:func:`normalize_values`; an all-zero slice stays
zero), so every chirp or frame uses the code's whole range; decoded outputs
are then in those normalised units.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

__all__ = ["N_PARTS", "PartLayout", "combine_parts", "normalize_values", "split_values"]

#: How signed/complex values are laid out on the trailing ``part`` axis.
PartLayout = Literal["none", "re_im", "signed", "re_im_signed"]

#: Size of the trailing ``part`` axis each layout adds (``none`` adds no axis).
N_PARTS: dict[str, int] = {"none": 0, "re_im": 2, "signed": 2, "re_im_signed": 4}


def normalize_values(x: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
    """Divide each slice over ``axes`` by its largest ``max(|Re|, |Im|)`` (zero slices stay 0).

    Examples
    --------
    >>> normalize_values(np.array([[2.0, -4.0], [0.0, 0.0]]), axes=(1,)).tolist()
    [[0.5, -1.0], [0.0, 0.0]]
    >>> normalize_values(np.array([3.0 - 6.0j]), axes=(0,)).tolist()
    [(0.5-1j)]
    """
    x = np.asarray(x)
    if not axes:
        return x
    peak = np.maximum(np.abs(np.real(x)), np.abs(np.imag(x))).max(axis=axes, keepdims=True)
    return x / np.where(peak > 0, peak, 1.0)


def split_values(x: np.ndarray, split: PartLayout) -> np.ndarray:
    """Spread values over a trailing ``part`` axis (see the module docstring).

    Examples
    --------
    >>> split_values(np.array([2.0 - 3.0j]), "re_im_signed").tolist()
    [[2.0, 0.0, 0.0, 3.0]]
    """
    x = np.asarray(x)
    if split == "none":
        return x
    if split == "re_im_signed" and x.dtype == np.complex128 and x.flags.c_contiguous:
        # (re, im) pairs as one float axis: each of the three operations in one call
        comps = x.reshape(-1).view(np.float64).reshape(*x.shape, 2)
        out = np.empty((*x.shape, 2, 2), np.float64)  # (component, sign) = the 4 parts
        np.maximum(comps, 0.0, out=out[..., 0])
        np.maximum(np.negative(comps), 0.0, out=out[..., 1])
        return out.reshape(*x.shape, 4)
    # as float64 (a view of complex128 or float64 values, a copy of anything else)
    re, im = np.real(x).astype(np.float64, copy=False), np.imag(x).astype(np.float64, copy=False)
    out = np.empty((*x.shape, 2 if split in ("re_im", "signed") else 4), np.float64)
    if split == "re_im":
        out[..., 0], out[..., 1] = re, im
        return out
    for i, comp in enumerate((re,) if split == "signed" else (re, im)):
        np.maximum(comp, 0.0, out=out[..., 2 * i])     # the same operations as
        np.negative(comp, out=out[..., 2 * i + 1])     # maximum(c, 0), maximum(−c, 0),
        np.maximum(out[..., 2 * i + 1], 0.0, out=out[..., 2 * i + 1])  # written in place
    return out


def combine_parts(y: np.ndarray, combine: PartLayout) -> np.ndarray:
    """Fold a trailing ``part`` axis back into values (inverse of :func:`split_values`).

    Examples
    --------
    >>> combine_parts(split_values(np.array([2.0 - 3.0j]), "re_im_signed"), "re_im_signed")
    array([2.-3.j])
    """
    if combine == "none":
        return y
    if combine == "re_im":
        return y[..., 0] + 1j * y[..., 1]
    if combine == "signed":
        return y[..., 0] - y[..., 1]
    if y.dtype != np.float64:
        return (y[..., 0] - y[..., 1]) + 1j * (y[..., 2] - y[..., 3])
    # a + 1j·b written into one complex array, the same floats: 1j·b is (0·b − 0) + (0 + b)j
    # and adding a gives (a + 0·b) + (0 + b)j (0·b: a zero of b's sign, NaN for b = ±inf)
    out = np.empty(y.shape[:-1], np.complex128)
    re, im = out.real, out.imag
    np.subtract(y[..., 0], y[..., 1], out=re)
    np.subtract(y[..., 2], y[..., 3], out=im)
    np.add(re, np.multiply(im, 0.0), out=re)
    np.add(im, 0.0, out=im)
    return out
