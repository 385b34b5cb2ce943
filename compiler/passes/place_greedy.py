"""The default placer of the ``place`` pass: first-fit decreasing with locality.

A placer is any function ``placer(demand, limits, affinity, n_cores) -> core``
(:data:`Placer`); the ``place`` pass takes it as an option.

Examples
--------
>>> import numpy as np
>>> greedy_placer(np.array([[3.0], [2.0], [2.0]]), np.array([4.0]),
...               np.zeros((3, 3)), None).tolist()
[0, 1, 1]
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

__all__ = ["Placer", "greedy_placer"]

#: ``placer(demand (n, 4), limits (4,), affinity (n, n), n_cores or None) -> core (n,)``,
#: core ``-1`` for a block that does not fit in ``n_cores``.
Placer = Callable[[np.ndarray, np.ndarray, object, int | None], np.ndarray]


def greedy_placer(demand: np.ndarray, limits: np.ndarray, affinity,
                  n_cores: int | None) -> np.ndarray:
    """First-fit decreasing with locality.

    Blocks are taken in order of decreasing dominant share ``max(demand / limits)``
    rounded to 5 % buckets, and within a bucket in Cuthill-McKee order of
    the affinity graph (connected blocks next to each other).  Each goes to the
    first core with room among, first, the cores of the blocks it exchanges most
    synapses with (``affinity``, heaviest first), then all open cores in order;
    else a new core is opened.  Deterministic.

    Parameters
    ----------
    demand : ndarray, shape (n, 4)
        Per block amounts in :data:`~compiler.hardware.BUDGETS` order.
    limits : ndarray, shape (4,)
        Per core limits (``inf`` = unbounded).
    affinity : sparse or dense (n, n)
        Symmetric weights between blocks (distinct source-target neuron pairs).
    n_cores : int or None
        Cores available (``None``: unbounded).

    Returns
    -------
    ndarray of int
        The core of each block; ``-1`` where none was left.
    """
    n = len(demand)
    if n == 0:  # nothing to place (a program without spiking stages)
        return np.zeros(0, np.int64)
    share = np.where(np.isfinite(limits), demand / np.where(np.isfinite(limits), limits, 1), 0)
    aff = sp.csr_matrix(affinity)
    rank = np.empty(n, np.int64)
    rank[reverse_cuthill_mckee(aff, symmetric_mode=True)[::-1]] = np.arange(n)  # Cuthill-McKee
    bucket = np.round(share.max(axis=1, initial=0.0) * 20)
    order = np.lexsort((rank, -bucket))
    core = np.full(n, -1, np.int64)
    free = np.empty((0, demand.shape[1]))
    for b in order:
        d = demand[b]
        lo, hi = aff.indptr[b], aff.indptr[b + 1]
        nbr, w = aff.indices[lo:hi], aff.data[lo:hi]
        placed = nbr[core[nbr] >= 0]
        cand = core[placed[np.argsort(-w[core[nbr] >= 0], kind="stable")]]
        fits_all = np.all(free >= d, axis=1)
        pick = next((c for c in cand if fits_all[c]), None)
        if pick is None and fits_all.any():
            pick = int(np.argmax(fits_all))
        if pick is None:
            if n_cores is not None and len(free) >= n_cores:
                continue
            free = np.vstack([free, limits])
            pick = len(free) - 1
        free[pick] -= d
        core[b] = pick
    return core
