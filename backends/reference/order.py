"""Ordering spike events by step: a stable linear-time sort where the step range allows.

Spike steps are small non-negative integers (``< n_steps``), so a stable sort of
them can use numpy's radix sort (``kind="stable"`` on 16-bit integers) instead
of a comparison sort: :func:`order_by_step` is the permutation that sorts
events by step, ties kept in their given order.

Examples
--------
>>> import numpy as np
>>> order_by_step(np.array([3, 1, 3, 0]), n_steps=4).tolist()
[3, 1, 0, 2]
>>> first_spike_steps(np.array([2, 0, 2]), np.array([1, 4, 5]), 3).tolist()
[4, -1, 1]
"""

from __future__ import annotations

import numpy as np

__all__ = ["events_of_first", "first_spike_steps", "order_by_step"]


def order_by_step(steps: np.ndarray, n_steps: int) -> np.ndarray:
    """The stable permutation sorting ``steps`` (ints in ``[0, n_steps)``) ascending
    (a one-pass radix sort when the steps fit a byte, two when they fit 16 bits)."""
    for narrow in (np.uint8, np.uint16):
        if n_steps <= np.iinfo(narrow).max + 1:
            return np.argsort(steps.astype(narrow), kind="stable")
    return np.argsort(steps, kind="stable")


def events_of_first(first: np.ndarray, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """``(flat, step)`` of first-spike steps (``-1``: none), ordered by step, ties by neuron.

    Examples
    --------
    >>> [a.tolist() for a in events_of_first(np.array([3, -1, 0, 3, 1, 0]), n_steps=5)]
    [[2, 5, 4, 0, 3], [0, 0, 1, 3, 3]]
    """
    flat = np.flatnonzero(first >= 0)
    step = first[flat]
    order = order_by_step(step, n_steps)  # flat is ascending: ties stay by neuron
    return flat[order], step[order]


def first_spike_steps(flat: np.ndarray, step: np.ndarray, n: int) -> np.ndarray:
    """First spike step of each of ``n`` neurons (``-1``: none) from events sorted by step."""
    first = np.full(n, -1, np.int64)
    if flat.size == 0:
        return first
    if np.bincount(flat, minlength=n).max() <= 1:  # at most one spike each (fire-once)
        first[flat] = step
        return first
    # the earliest step of each neuron: one unbuffered minimum per event (no sort); the
    # events are ordered by step, so this is the step of each neuron's first event
    big = np.iinfo(np.int64).max
    earliest = np.full(n, big, np.int64)
    np.minimum.at(earliest, flat, step)
    return np.where(earliest == big, -1, earliest)
