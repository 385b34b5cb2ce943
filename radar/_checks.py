"""Argument checks shared by the conventional DSP modules (each raises RadarConfigError)."""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError


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
