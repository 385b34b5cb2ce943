"""Checks shared by the projection kinds: finite weights and per-synapse integer delays.

Examples
--------
>>> import numpy as np
>>> int_delays(np.array([0, 2]), (2,), "p").tolist(), int_delays(np.zeros(2, int), (2,), "p")
([0, 2], None)
"""

from __future__ import annotations

import numpy as np

from ir.errors import NetworkError

__all__ = ["finite_weights", "int_delays"]


def int_delays(delays: np.ndarray | None, shape: tuple[int, ...], pid: str) -> np.ndarray | None:
    """``delays`` as int64 of ``shape`` (``None`` when absent or all zero); raise on a bad one."""
    if delays is None:
        return None
    d = np.asarray(delays)
    if d.shape != shape:
        raise NetworkError(
            f"projection {pid!r}: delays have shape {d.shape}, expected {shape} (one per synapse)",
            node=pid,
        )
    if d.size and (not np.issubdtype(d.dtype, np.integer) or d.min() < 0):
        raise NetworkError(
            f"projection {pid!r}: delays must be non-negative integers (steps), got dtype "
            f"{d.dtype} and minimum {d.min() if d.size else 'n/a'}",
            node=pid,
        )
    d = d.astype(np.int64)
    return None if not d.any() else d


def finite_weights(w: np.ndarray, pid: str) -> np.ndarray:
    """``w`` as float64; raise :class:`~ir.errors.NetworkError` on NaN or Inf."""
    w = np.asarray(w, dtype=np.float64)
    if not np.all(np.isfinite(w)):
        raise NetworkError(f"projection {pid!r}: weights contain NaN or Inf", node=pid)
    return w
