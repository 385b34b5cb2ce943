"""Sets of integer keys by sorting: the distinct values of an int array, and each one's index.

``np.unique`` on large int64 arrays takes the hash-table path in numpy ≥ 2.3, which
is one to two orders of magnitude slower than a sort for the key arrays of the
allocation passes (millions of ``block · n + neuron`` keys); these two functions
give the same results as ``np.unique(x)`` and ``np.unique(x, return_inverse=True)``
for a 1-d integer array, by one sort.

Examples
--------
>>> import numpy as np
>>> unique_keys(np.array([5, 1, 5, 3])).tolist()
[1, 3, 5]
>>> keys, inverse = unique_inverse(np.array([5, 1, 5, 3]))
>>> keys.tolist(), inverse.tolist()
([1, 3, 5], [2, 0, 2, 1])
"""

from __future__ import annotations

import numpy as np

__all__ = ["unique_keys", "unique_inverse"]


def _first_of_runs(s: np.ndarray) -> np.ndarray:
    """Whether each element of a sorted array differs from its predecessor."""
    new = np.empty(s.size, bool)
    new[:1] = True
    np.not_equal(s[1:], s[:-1], out=new[1:])
    return new


def unique_keys(x: np.ndarray) -> np.ndarray:
    """The sorted distinct values of the 1-d integer array ``x`` (``np.unique(x)``)."""
    s = np.sort(x, kind="stable")
    return s[_first_of_runs(s)]


def unique_inverse(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``keys, inverse`` with ``keys[inverse] == x`` (``np.unique(x, return_inverse=True)``)."""
    order = np.argsort(x, kind="stable")
    s = x[order]
    new = _first_of_runs(s)
    inverse = np.empty(x.size, np.int64)
    inverse[order] = np.cumsum(new) - 1
    return s[new], inverse
