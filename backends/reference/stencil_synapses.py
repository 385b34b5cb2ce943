"""How many taps of a stencil land inside the map, per source neuron, from per-axis tables.

A tap of a stencil delivery (:mod:`backends.reference.stencil`) lands inside the map when
it does on every clipped axis (a wrapped axis never loses one), so over one clipped axis
the count per source neuron is a row sum of the ``coordinate × tap`` validity table of
that axis, and over two it is one product of the two tables (exact in float64: the counts
stay far below 2^53), broadcast over the other axes.

Examples
--------
>>> import numpy as np
>>> inside_counts(np.array([[-1], [1]]), (0,), (False,), (0,), (4,), (4,)).tolist()
[1, 2, 2, 1]
"""

from __future__ import annotations

import numpy as np

__all__ = ["inside_counts"]


def inside_counts(offsets: np.ndarray, map_axes: tuple[int, ...], wrap: tuple[bool, ...],
                  src_axis_of: tuple[int, ...], src_dims: tuple[int, ...],
                  tgt_dims: tuple[int, ...]) -> np.ndarray | None:
    """Per source neuron (flat, memory order), the taps landing inside the map.

    Parameters
    ----------
    offsets : ndarray, shape (n_taps, n_map_axes)
        The taps' offsets (a spike at ``x`` reaches ``x − o``).
    map_axes, wrap : tuple
        The target axes the stencil runs over, and whether each wraps.
    src_axis_of, src_dims, tgt_dims : tuple of int
        Per target axis the source axis holding it; the source and target sizes.

    Returns
    -------
    ndarray of int64 or None
        None when more than two axes clip (count those tap by tap).
    """
    clipped = [j for j in range(len(map_axes)) if not wrap[j]]
    if len(clipped) > 2:
        return None
    tables, axes = [], []
    for j in clipped:
        src_axis = src_axis_of[map_axes[j]]
        c = np.arange(src_dims[src_axis])[:, None] - offsets[None, :, j]
        tables.append((c >= 0) & (c < tgt_dims[map_axes[j]]))
        axes.append(src_axis)
    if not tables:
        per = np.full((), offsets.shape[0], np.int64)
    elif len(tables) == 1:
        per = tables[0].sum(axis=1, dtype=np.int64)
    else:
        per = np.rint(tables[0].astype(np.float64) @ tables[1].T.astype(np.float64))
        per = per.astype(np.int64)
        if axes[0] > axes[1]:
            per, axes = per.T, axes[::-1]
    shape = [1] * len(src_dims)
    for a in axes:
        shape[a] = src_dims[a]
    counts = np.broadcast_to(per.reshape(shape), src_dims)
    return np.ascontiguousarray(counts, dtype=np.int64).reshape(-1)
