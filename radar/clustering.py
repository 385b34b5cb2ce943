r"""DBSCAN clustering of CFAR detections into a fixed-capacity cluster table.

A target spreads over several range-Doppler cells (window main lobes, range
migration), so a CFAR mask holds a few *clusters* of detections per target.
This module groups the detected cells with scikit-learn's DBSCAN and reduces
each group to one row of a table of fixed shape ``[max_clusters, N_FEATURES]``.

Distances.  Cell :math:`(i, j)` of a map ``[range, doppler]`` of shape
:math:`(N_r, N_d)` sits at :math:`(s_r i, s_d j)` with ``axes_scale`` =
:math:`(s_r, s_d)`.  Doppler is circular (bin :math:`N_d - 1` neighbours bin 0),
so the distance between two cells is

.. math:: d = \sqrt{s_r^2 \Delta_r^2 + s_d^2 \min(|\Delta_d|, N_d - |\Delta_d|)^2}

(range is not wrapped).  The neighbour graph with :math:`d \le \varepsilon` is
built with a periodic k-d tree (``scipy.spatial.cKDTree(boxsize=...)``; a wrapped
axis has period :math:`s N`, an unwrapped one a period larger than the map plus
:math:`\varepsilon`, so it never wraps) and passed to DBSCAN as a sparse
precomputed distance matrix.  Two detections share a cluster when they are
connected through *core* cells, i.e. cells with at least ``min_samples``
detections (themselves included) within :math:`\varepsilon`; with
``min_samples = 1`` every detection is a core cell and the clusters are the
connected components of the :math:`\varepsilon`-graph.  Non-core cells that no
core cell reaches are noise and dropped.

Table rows (features :data:`FEATURES`).  For a cluster :math:`C` with powers
:math:`p_c \ge 0` and peak cell :math:`c^* = \arg\max_{c \in C} p_c` (ties: the
lowest flat index), the centroid on each axis is the power-weighted mean of the
offsets from the peak, wrapped into :math:`[-\lfloor N/2 \rfloor, N - \lfloor N/2
\rfloor)` on a circular axis, added back to the peak and reduced modulo
:math:`N`:

.. math:: \bar x = \Big(x^* + \frac{\sum_{c} p_c\, \delta(x_c - x^*)}{\sum_c p_c}\Big)
          \bmod N

(no wrapping and no modulo on a linear axis; equal weights if
:math:`\sum_c p_c = 0`).  Unwrapping around the peak gives the right centroid
for any cluster narrower than half the Doppler axis on each side of its peak.
Rows are sorted by descending peak power, ties by the peak cell's (range,
Doppler) bins; the first ``max_clusters`` are kept (the weakest clusters are
dropped) and padding rows are all zero (``valid = 0``).

Examples
--------
>>> import numpy as np
>>> mask = np.zeros((6, 8), dtype=bool)
>>> mask[1, [0, 7]] = True          # one target across the Doppler wrap
>>> mask[4, 3] = True
>>> power = np.where(mask, 1.0, 0.0); power[1, 7] = 3.0; power[4, 3] = 2.0
>>> cluster_detections(mask, power, eps_bins=1.0, max_clusters=3).tolist()
[[1.0, 1.0, 7.25, 2.0, 3.0], [1.0, 4.0, 3.0, 1.0, 2.0], [0.0, 0.0, 0.0, 0.0, 0.0]]
"""

from __future__ import annotations

import numpy as np

from ir.errors import RadarConfigError

__all__ = ["FEATURES", "N_FEATURES", "cluster_detections", "cluster_table", "label_detections"]

FEATURES: tuple[str, ...] = ("valid", "range_bin", "doppler_bin", "n_cells", "peak_power")
"""Columns of a cluster table: 1/0, centroid bins (fractional), cells, peak cell's power
(the IR's :data:`ir.ops.host.CLUSTER_FEATURES` is this tuple: the domain owns the layout)."""

N_FEATURES = len(FEATURES)


def _check_map(mask: np.ndarray, power: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    mask = np.asarray(mask)
    if mask.dtype != np.bool_ or mask.ndim != 2:
        raise RadarConfigError(f"clustering: mask must be a 2-D bool array [range, doppler]; got "
                               f"{mask.dtype} of shape {mask.shape}")
    if power is None:
        return mask, np.ones(mask.shape)
    power = np.asarray(power, dtype=np.float64)
    if power.shape != mask.shape:
        raise RadarConfigError(f"clustering: power has shape {power.shape} but the mask has "
                               f"{mask.shape}; pass the map the mask was detected on")
    if not np.isfinite(power[mask]).all() or (power[mask] < 0).any():
        raise RadarConfigError("clustering: power at detected cells must be finite and >= 0; "
                               "pass a power or amplitude map")
    return mask, power


def label_detections(mask: np.ndarray, *, eps_bins: float = 1.5, min_samples: int = 1,
                     axes_scale: tuple[float, float] = (1.0, 1.0),
                     wrap: tuple[bool, bool] = (False, True)) -> np.ndarray:
    """DBSCAN labels of the detected cells of one map (see the module docstring).

    Parameters
    ----------
    mask : ndarray of bool, shape (n_range, n_doppler)
        Detections.
    eps_bins : float
        Neighbourhood radius :math:`\\varepsilon` in scaled bins (> 0).
    min_samples : int
        Detections within :math:`\\varepsilon` (the cell included) that make a core cell.
    axes_scale : tuple of 2 float
        Bins -> distance units per axis (> 0), e.g. ``(1, 0.5)`` counts Doppler bins half.
    wrap : tuple of 2 bool
        Which axes are circular (default: Doppler).

    Returns
    -------
    ndarray of int64, shape of ``mask``
        Cluster label of each detected cell (0, 1, … in order of first flat index);
        -1 for cells not detected and for DBSCAN noise.

    Raises
    ------
    RadarConfigError
        Non-bool or non-2-D mask, ``eps_bins <= 0``, ``min_samples < 1`` or a scale <= 0.

    Examples
    --------
    >>> m = np.array([[1, 0, 0, 1], [0, 0, 0, 0], [0, 1, 0, 0]], dtype=bool)
    >>> label_detections(m, eps_bins=1.0).tolist()
    [[0, -1, -1, 0], [-1, -1, -1, -1], [-1, 1, -1, -1]]
    >>> label_detections(m, eps_bins=1.0, wrap=(False, False)).tolist()
    [[0, -1, -1, 1], [-1, -1, -1, -1], [-1, 2, -1, -1]]
    """
    from scipy.spatial import cKDTree
    from sklearn.cluster import DBSCAN

    mask, _ = _check_map(mask, None)
    scale = np.asarray(axes_scale, dtype=np.float64)
    if not eps_bins > 0 or min_samples < 1 or scale.shape != (2,) or not (scale > 0).all():
        raise RadarConfigError(f"clustering: need eps_bins > 0, min_samples >= 1 and two "
                               f"axes_scale > 0; got eps_bins={eps_bins}, min_samples="
                               f"{min_samples}, axes_scale={tuple(axes_scale)}")
    labels = np.full(mask.shape, -1, dtype=np.int64)
    cells = np.argwhere(mask)
    if len(cells) == 0:
        return labels
    sizes = np.asarray(mask.shape, dtype=np.float64)
    box = np.where(np.asarray(wrap, dtype=bool), sizes * scale, sizes * scale + eps_bins + 1.0)
    tree = cKDTree(cells * scale, boxsize=box)
    dist = tree.sparse_distance_matrix(tree, eps_bins, output_type="coo_matrix").tocsr()
    found = DBSCAN(eps=eps_bins, min_samples=min_samples, metric="precomputed").fit(dist)
    raw = found.labels_
    # relabel in order of each cluster's first cell (argwhere is in flat-index order)
    keep = raw >= 0
    _, first, dense = np.unique(raw[keep], return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    labels[tuple(cells[keep].T)] = rank[dense]
    return labels


def cluster_table(labels: np.ndarray, power: np.ndarray | None = None, *,
                  max_clusters: int = 16,
                  wrap: tuple[bool, bool] = (False, True)) -> np.ndarray:
    """Reduce labelled cells to the fixed-capacity table (rows as in the module docstring).

    Parameters
    ----------
    labels : ndarray of int, shape (n_range, n_doppler)
        Labels from :func:`label_detections` (-1: no cluster).
    power : ndarray, optional
        Power (or amplitude) map of the same shape; None weighs every cell 1.
    max_clusters : int
        Rows of the table (>= 1).
    wrap : tuple of 2 bool
        Circular axes (centroids are averaged around the peak there).

    Returns
    -------
    ndarray of float64, shape (max_clusters, N_FEATURES)

    Raises
    ------
    RadarConfigError
        Bad shapes, negative or non-finite power at a labelled cell, ``max_clusters < 1``.

    Examples
    --------
    >>> lab = np.array([[-1, 0, 0], [1, -1, -1]])
    >>> cluster_table(lab, np.array([[0.0, 1.0, 3.0], [5.0, 0.0, 0.0]]), max_clusters=2,
    ...               wrap=(False, False)).tolist()
    [[1.0, 1.0, 0.0, 1.0, 5.0], [1.0, 0.0, 1.75, 2.0, 3.0]]
    """
    labels = np.asarray(labels)
    mask, power = _check_map(labels >= 0, power)
    if max_clusters < 1:
        raise RadarConfigError(f"clustering: max_clusters={max_clusters} must be >= 1")
    table = np.zeros((max_clusters, N_FEATURES))
    flat = np.flatnonzero(mask)
    if flat.size == 0:
        return table
    lab = labels.reshape(-1)[flat]
    p = power.reshape(-1)[flat]
    order = np.lexsort((flat, -p, lab))            # per label: strongest, then first cell
    uniq, start = np.unique(lab[order], return_index=True)
    peak = flat[order[start]]
    n_lab = int(uniq.max()) + 1
    n_cells = np.bincount(lab, minlength=n_lab)[uniq]
    weight_sum = np.bincount(lab, weights=p, minlength=n_lab)[uniq]
    uniform = weight_sum <= 0
    w = np.where(uniform[np.searchsorted(uniq, lab)], 1.0, p)
    w_sum = np.where(uniform, n_cells, weight_sum)
    centroid = []
    for axis, (coord, peak_coord) in enumerate(zip(np.unravel_index(flat, mask.shape),
                                                   np.unravel_index(peak, mask.shape),
                                                   strict=True)):
        n = mask.shape[axis]
        ref = peak_coord[np.searchsorted(uniq, lab)]
        delta = coord - ref
        if wrap[axis]:
            delta = np.mod(delta + n // 2, n) - n // 2
        mean = np.bincount(lab, weights=w * delta, minlength=n_lab)[uniq] / w_sum
        c = peak_coord + mean
        centroid.append(np.mod(c, n) if wrap[axis] else c)
    peak_r, peak_d = np.unravel_index(peak, mask.shape)
    rows = np.lexsort((peak_d, peak_r, -power.reshape(-1)[peak]))[:max_clusters]
    table[: len(rows)] = np.column_stack([np.ones(len(rows)), centroid[0][rows],
                                          centroid[1][rows], n_cells[rows],
                                          power.reshape(-1)[peak][rows]])
    return table


def cluster_detections(mask: np.ndarray, power: np.ndarray | None = None, *,
                       eps_bins: float = 1.5, min_samples: int = 1, max_clusters: int = 16,
                       axes_scale: tuple[float, float] = (1.0, 1.0),
                       wrap: tuple[bool, bool] = (False, True)) -> np.ndarray:
    """Cluster the detections of one or more maps into fixed-capacity tables.

    Parameters
    ----------
    mask : ndarray of bool, shape (..., n_range, n_doppler)
        CFAR detections; leading axes are a batch (each map is clustered alone).
    power : ndarray, optional
        The map the detections were made on (same shape; weights and peak power);
        None weighs every cell 1 (``peak_power`` is then 1).
    eps_bins, min_samples, axes_scale, wrap
        See :func:`label_detections`.
    max_clusters : int
        Rows per table.

    Returns
    -------
    ndarray of float64, shape (..., max_clusters, N_FEATURES)
        One table per map; columns :data:`FEATURES`.

    Raises
    ------
    RadarConfigError
        As :func:`label_detections` and :func:`cluster_table`.

    Examples
    --------
    >>> m = np.zeros((2, 4, 4), dtype=bool); m[1, 2, 1:3] = True
    >>> cluster_detections(m, max_clusters=1)[:, 0].tolist()
    [[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 1.5, 2.0, 1.0]]
    """
    mask = np.asarray(mask)
    if mask.ndim < 2:
        raise RadarConfigError(f"clustering: mask needs at least 2 axes; got shape {mask.shape}")
    if power is not None and np.shape(power) != mask.shape:
        raise RadarConfigError(f"clustering: power has shape {np.shape(power)} but the mask has "
                               f"{mask.shape}; pass the map the mask was detected on")
    batch = mask.shape[:-2]
    maps = mask.reshape(-1, *mask.shape[-2:])
    powers = None if power is None else np.asarray(power).reshape(maps.shape)
    out = np.zeros((len(maps), max(int(max_clusters), 1), N_FEATURES))
    for k, m in enumerate(maps):  # one DBSCAN per map (frames are independent)
        labels = label_detections(m, eps_bins=eps_bins, min_samples=min_samples,
                                  axes_scale=axes_scale, wrap=wrap)
        out[k] = cluster_table(labels, None if powers is None else powers[k],
                               max_clusters=max_clusters, wrap=wrap)
    return out.reshape(*batch, *out.shape[1:])
