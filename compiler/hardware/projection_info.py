r"""What the block counting needs of one projection, computed once per projection and shapes.

For a matrix projection from ``S`` (contracting ``contract``) to ``T`` (producing
``produce``): the non-zero pattern :math:`[W_{cp} \ne 0]` and its transpose, the
in-degree :math:`\sum_c [W_{cp} \ne 0]` of every column ``p``, the rows ``c`` with a
synapse, and the flat source offset :math:`\sum_{a \in \text{contract}} c_a\,
\text{stride}_S(a)` of every row.  For a stencil: its non-zero tap offsets and
the map of source positions with at least one target.  (The non-zero pattern
itself is remembered per projection: :func:`~compiler.hardware.synapses.nonzero_pattern`.)

Examples
--------
>>> import numpy as np
>>> from compiler.snn import MatrixProjection, Population
>>> x = Population(id="x", shape={"rep": 2, "i": 3}, source=True)
>>> y = Population(id="y", shape={"rep": 2, "o": 2})
>>> w = MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
...                      weights=np.array([[1., 0], [1, 0], [0, 0]]))
>>> info = projection_info(w, x, y)
>>> info.indeg.tolist(), info.rownz.tolist(), info.offsets.tolist()
([2, 0], [True, True, False], [0, 1, 2])
>>> has_synapse_out(info, x, np.arange(6)).tolist()
[True, True, False, True, True, False]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from compiler.hardware.synapses import (
    coords,
    nonzero_pattern,
    ravel,
    stencil_degree_map,
    strides,
)
from compiler.snn import MatrixProjection, Population, StencilProjection

__all__ = ["ProjectionInfo", "has_synapse_out", "projection_info"]


@dataclass(frozen=True, eq=False)
class ProjectionInfo:
    """What the per-chunk counting needs of one projection, computed once."""

    proj: MatrixProjection | StencilProjection
    pattern: sp.csr_matrix | None = None     # matrix: (n_in, n_out) non-zero pattern
    pattern_t: sp.csr_matrix | None = None   # matrix: its transpose, CSR
    indeg: np.ndarray | None = None          # matrix: synapses per column
    rownz: np.ndarray | None = None          # matrix: rows with a synapse
    offsets: np.ndarray | None = None        # matrix: flat source offset per row; stencil: taps
    out_map: np.ndarray | None = None        # stencil: has-target map over the stencil axes


def projection_info(proj, src: Population, tgt: Population) -> ProjectionInfo:
    """Precompute what the per-chunk counting needs of ``proj`` (from ``src`` to ``tgt``)."""
    if isinstance(proj, StencilProjection):
        taps = np.argwhere(proj.kernel != 0) - np.array(proj.radius)
        return ProjectionInfo(proj, offsets=taps,
                              out_map=stencil_degree_map(proj, src, incoming=False) > 0)
    pattern = nonzero_pattern(proj)
    s_str = strides(src)
    idx = np.unravel_index(np.arange(proj.n_in), [src.shape[a] for a in proj.contract])
    off = np.zeros(proj.n_in, np.int64)
    for a, c in zip(proj.contract, idx, strict=True):
        off += c * s_str[a]
    return ProjectionInfo(proj, pattern=pattern, pattern_t=pattern.T.tocsr(),
                          indeg=np.asarray(pattern.sum(axis=0)).ravel().astype(np.int64),
                          rownz=np.asarray(pattern.sum(axis=1)).ravel() > 0, offsets=off)


def has_synapse_out(info: ProjectionInfo, pop: Population, flat: np.ndarray) -> np.ndarray:
    """Whether each neuron of ``pop`` (flat indices) has a synapse in the projection."""
    proj = info.proj
    if isinstance(proj, StencilProjection):
        return info.out_map[tuple(coords(pop, flat, proj.axes))]
    c = ravel(coords(pop, flat, proj.contract), [pop.shape[a] for a in proj.contract])
    return info.rownz[c]
