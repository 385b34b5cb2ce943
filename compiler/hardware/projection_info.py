r"""What the block counting needs of one projection, computed once per projection and shapes.

For a matrix projection from ``S`` (contracting ``contract``) to ``T`` (producing
``produce``): the non-zero pattern :math:`[W_{cp} \ne 0]` and its transpose, the
in-degree :math:`\sum_c [W_{cp} \ne 0]` of every column ``p``, the rows ``c`` with a
synapse, and the flat source offset :math:`\sum_{a \in \text{contract}} c_a\,
\text{stride}_S(a)` of every row.  For a stencil: its non-zero tap offsets and
the map of source positions with at least one target.  (The non-zero pattern
itself is the projection's: ``MatrixProjection.nonzero_pattern``.)

Each kind has its info class, :class:`MatrixInfo` or :class:`StencilInfo`, and
the info answers the counting for its kind: which source neurons have a synapse
out (:meth:`~MatrixInfo.has_synapse_out`), the ``(block, source)`` pairs that
target neurons reach (:meth:`~MatrixInfo.reached`), whether its entries are
shared by target column (``shared_matrix``) and the kernel taps stored once per
block (``kernel_taps``).  :func:`projection_info` picks the info class from the
explicit table :data:`INFO_BUILDERS`, keyed by the projection *type*: the
hardware model is a layer above :mod:`compiler.snn`, which must not know it.

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
>>> b, s = info.reached(x, y, np.array([0, 1]), np.array([0, 0]))
>>> sorted(zip(b.tolist(), s.tolist()))
[(0, 0), (0, 1)]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.sparse as sp

from compiler.hardware.intsets import unique_inverse
from compiler.hardware.synapses import coords, ravel, strides
from compiler.snn import MatrixProjection, Population, Projection, StencilProjection
from ir.errors import NetworkError

__all__ = ["INFO_BUILDERS", "MatrixInfo", "ProjectionInfo", "StencilInfo", "has_synapse_out",
           "projection_info"]


@dataclass(frozen=True, eq=False)
class MatrixInfo:
    """What the per-chunk counting needs of one matrix projection, computed once."""

    proj: MatrixProjection
    pattern: sp.csr_matrix      # (n_in, n_out) non-zero pattern
    pattern_t: sp.csr_matrix    # its transpose, CSR
    indeg: np.ndarray           # synapses per column
    rownz: np.ndarray           # rows with a synapse
    offsets: np.ndarray         # flat source offset per row
    #: Entries are shared by target column (``indeg``), so sharing is counted per column.
    shared_matrix: ClassVar[bool] = True
    #: Entries stored once per block whatever neurons it holds (a kernel's taps).
    kernel_taps: ClassVar[int] = 0
    #: Source neurons one target neuron reaches per tap, for the sweep's chunking.
    reach_taps: ClassVar[int] = 1

    @classmethod
    def of(cls, proj: MatrixProjection, src: Population, tgt: Population) -> MatrixInfo:
        """Precompute the pattern, in-degrees, live rows and row offsets of ``proj``."""
        pattern = proj.nonzero_pattern
        s_str = strides(src)
        idx = np.unravel_index(np.arange(proj.n_in), [src.shape[a] for a in proj.contract])
        off = np.zeros(proj.n_in, np.int64)
        for a, c in zip(proj.contract, idx, strict=True):
            off += c * s_str[a]
        return cls(proj, pattern=pattern, pattern_t=pattern.T.tocsr(),
                   indeg=np.asarray(pattern.sum(axis=0)).ravel().astype(np.int64),
                   rownz=np.asarray(pattern.sum(axis=1)).ravel() > 0, offsets=off)

    def has_synapse_out(self, pop: Population, flat: np.ndarray) -> np.ndarray:
        """Whether each source neuron of ``pop`` (flat indices) has a synapse: its row is live."""
        proj = self.proj
        c = ravel(pop, flat, proj.contract)
        return self.rownz[c]

    def reached(self, src: Population, tgt: Population, flat: np.ndarray,
                blk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distinct ``(block, source)`` pairs reached by target neurons ``flat`` of ``blk``."""
        proj = self.proj
        rep_axes = tuple(a for a in tgt.axes if a not in proj.produce)
        p = ravel(tgt, flat, proj.produce)
        s_str = strides(src)
        base = np.zeros_like(flat)
        for a, c in zip(rep_axes, coords(tgt, flat, rep_axes), strict=True):
            base += c * s_str[a]
        pair_key, pair_id = unique_inverse(blk * src.size + base)
        ind = sp.csr_matrix((np.ones(flat.size, bool), (pair_id, p)),
                            shape=(pair_key.size, proj.n_out))
        hit = (ind @ self.pattern_t).tocsr()
        row = np.repeat(np.arange(pair_key.size), np.diff(hit.indptr))
        return (pair_key // src.size)[row], (pair_key % src.size)[row] + self.offsets[hit.indices]


@dataclass(frozen=True, eq=False)
class StencilInfo:
    """What the per-chunk counting needs of one stencil projection, computed once."""

    proj: StencilProjection
    offsets: np.ndarray         # (n_taps, n_axes) centred offsets of the non-zero taps
    out_map: np.ndarray         # has-target map over the stencil axes
    shared_matrix: ClassVar[bool] = False

    @classmethod
    def of(cls, proj: StencilProjection, src: Population, tgt: Population) -> StencilInfo:
        """Precompute the tap offsets and the has-target map of ``proj``."""
        return cls(proj, offsets=proj.tap_offsets(),
                   out_map=proj.degree_map(src, incoming=False) > 0)

    @property
    def kernel_taps(self) -> int:
        """The kernel's taps: stored once per block whatever neurons it holds."""
        return len(self.offsets)

    @property
    def reach_taps(self) -> int:
        """Source neurons one target neuron reaches (its taps)."""
        return len(self.offsets)

    def has_synapse_out(self, pop: Population, flat: np.ndarray) -> np.ndarray:
        """Whether each source neuron of ``pop`` (flat indices) reaches a target in the map."""
        return self.out_map[tuple(coords(pop, flat, self.proj.axes))]

    def reached(self, src: Population, tgt: Population, flat: np.ndarray,
                blk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(block, source)`` pairs reached by target neurons ``flat`` (one per live tap)."""
        proj, offsets = self.proj, self.offsets
        n_taps = len(offsets)
        cs = coords(tgt, flat, proj.axes)
        st = strides(tgt)
        src_idx = np.repeat(flat[:, None], n_taps, axis=1)
        valid = np.ones((flat.size, n_taps), bool)
        for i, a in enumerate(proj.axes):
            c = cs[i][:, None] + offsets[None, :, i]
            n = tgt.shape[a]
            if proj.edge[i] == "wrap":
                c = c % n
            else:
                valid &= (c >= 0) & (c < n)
            src_idx += (c - cs[i][:, None]) * st[a]
        return np.broadcast_to(blk[:, None], valid.shape)[valid], src_idx[valid]


ProjectionInfo = MatrixInfo | StencilInfo

#: Info builders by projection type, ``(projection, source, target) -> info``.
INFO_BUILDERS: dict[type, Callable[..., ProjectionInfo]] = {
    MatrixProjection: MatrixInfo.of,
    StencilProjection: StencilInfo.of,
}


def projection_info(proj: Projection, src: Population, tgt: Population) -> ProjectionInfo:
    """Precompute what the per-chunk counting needs of ``proj`` (from ``src`` to ``tgt``).

    Raises
    ------
    NetworkError
        For a projection type without an entry in :data:`INFO_BUILDERS`.
    """
    build = INFO_BUILDERS.get(type(proj))
    if build is None:
        raise NetworkError(f"projection {proj.id!r}: the hardware model has no counting for "
                           f"{type(proj).__name__}; known: "
                           f"{sorted(t.__name__ for t in INFO_BUILDERS)}", node=proj.id)
    return build(proj, src, tgt)


def has_synapse_out(info: ProjectionInfo, pop: Population, flat: np.ndarray) -> np.ndarray:
    """Whether each neuron of ``pop`` (flat indices) has a synapse in the projection."""
    return info.has_synapse_out(pop, flat)
