r"""The matrix projection kind: one weight matrix along named axes, shared over the rest.

``W`` of shape ``(n_in, n_out)`` maps the flattened source axes ``contract`` to
the flattened target axes ``produce``; every other axis (a *repetition* axis) is
in both populations with the same size, so the matrix is applied
:math:`R = |S| / n_{in}` times.  The kind answers the projection protocol
(:class:`compiler.snn.projections.ProjectionKind`) for itself:

* stored weights: the dense ``W`` or the sparse COO ``values``;
* nominal synapse instances :math:`R \cdot \mathrm{nnz}(W)` (stored zeros excluded);
* wired synapses :math:`R \cdot |\{(c, p) : W_{cp} \ne 0\}|` (duplicate COO entries once);
* repetition axes: the target axes not in ``produce``.

Examples
--------
>>> import numpy as np
>>> from compiler.snn.network import Population
>>> x = Population(id="x", shape={"rep": 3, "i": 2}, source=True)
>>> y = Population(id="y", shape={"rep": 3, "o": 2})
>>> w = MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
...                      weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
>>> w.repetitions(x), w.n_synapse_instances(x, y), w.wired_synapses(x, y)
(3, 9, 9)
>>> sorted(w.repetition_axes(y)), w.min_delay()
(['rep'], 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from math import prod
from typing import TYPE_CHECKING, Literal

import numpy as np
import scipy.sparse as sp

from compiler.snn.projection_checks import finite_weights as _finite_weights
from compiler.snn.projection_checks import int_delays as _int_delays
from ir.errors import NetworkError

if TYPE_CHECKING:
    from compiler.snn.network import Population

__all__ = ["MatrixProjection"]


@dataclass(frozen=True, eq=False)
class MatrixProjection:
    """A weight matrix along named axes, shared over the repetition axes.

    Parameters
    ----------
    id, source, target : str
        Projection id and the source/target population ids.
    contract : tuple of str
        Source axes read by the matrix (flattened row-major in this order).
    produce : tuple of str
        Target axes written by the matrix (flattened row-major in this order).
    weights : ndarray of shape (n_in, n_out), optional
        Dense weights.  Give either ``weights`` or the COO triple.
    rows, cols, values : ndarray, optional
        Sparse weights in COO form (``W[rows[i], cols[i]] = values[i]``).
    delays : ndarray of int, optional
        Per-synapse delays in steps, shaped like ``weights`` or ``values``.
    origin : dict
        Provenance: ``{"node": <radar-IR node id>, "motif": <motif name>}``.
    """

    id: str
    source: str
    target: str
    contract: tuple[str, ...]
    produce: tuple[str, ...]
    weights: np.ndarray | None = None
    rows: np.ndarray | None = None
    cols: np.ndarray | None = None
    values: np.ndarray | None = None
    n_in_out: tuple[int, int] | None = None
    delays: np.ndarray | None = None
    origin: dict[str, str] = field(default_factory=dict)
    kind: Literal["matrix"] = "matrix"

    def __post_init__(self) -> None:
        pid = self.id
        set_ = object.__setattr__
        set_(self, "contract", tuple(self.contract))
        set_(self, "produce", tuple(self.produce))
        dense = self.weights is not None
        sparse = self.values is not None
        if dense == sparse:
            raise NetworkError(
                f"projection {pid!r}: give exactly one of dense `weights` or sparse "
                "`rows/cols/values` (with `n_in_out`)",
                node=pid,
            )
        if dense:
            w = _finite_weights(self.weights, pid)
            if w.ndim != 2:
                raise NetworkError(
                    f"projection {pid!r}: weights must be 2-D (n_in, n_out), got shape {w.shape}",
                    node=pid,
                )
            set_(self, "weights", w)
            set_(self, "n_in_out", (int(w.shape[0]), int(w.shape[1])))
            set_(self, "delays", _int_delays(self.delays, w.shape, pid))
        else:
            if self.rows is None or self.cols is None or self.n_in_out is None:
                raise NetworkError(
                    f"projection {pid!r}: sparse weights need rows, cols, values and n_in_out",
                    node=pid,
                )
            vals = _finite_weights(self.values, pid).ravel()
            rows = np.asarray(self.rows).astype(np.int64).ravel()
            cols = np.asarray(self.cols).astype(np.int64).ravel()
            n_in, n_out = (int(x) for x in self.n_in_out)
            if not (rows.shape == cols.shape == vals.shape):
                raise NetworkError(
                    f"projection {pid!r}: rows, cols and values differ in length "
                    f"({rows.size}, {cols.size}, {vals.size})",
                    node=pid,
                )
            if rows.size and (rows.min() < 0 or rows.max() >= n_in or cols.min() < 0
                              or cols.max() >= n_out):
                raise NetworkError(
                    f"projection {pid!r}: a sparse index is outside the ({n_in}, {n_out}) matrix",
                    node=pid,
                )
            set_(self, "values", vals)
            set_(self, "rows", rows)
            set_(self, "cols", cols)
            set_(self, "n_in_out", (n_in, n_out))
            set_(self, "delays", _int_delays(self.delays, vals.shape, pid))

    @property
    def is_sparse(self) -> bool:
        """Whether the weights are stored in COO form."""
        return self.weights is None

    @property
    def n_in(self) -> int:
        """Number of matrix rows (flattened ``contract`` axes)."""
        return self.n_in_out[0]

    @property
    def n_out(self) -> int:
        """Number of matrix columns (flattened ``produce`` axes)."""
        return self.n_in_out[1]

    @cached_property
    def n_synapses(self) -> int:
        """Stored synapses of one instance: the non-zero weights (dense or sparse; counted once)."""
        return int(np.count_nonzero(self.weights if self.weights is not None else self.values))

    @property
    def max_delay(self) -> int:
        """The largest synaptic delay in steps (0 without delays)."""
        return 0 if self.delays is None else int(self.delays.max())

    def by_delay(self) -> dict[int, sp.csr_matrix]:
        """The weights split by delay: ``{d: W_d}`` with ``W = Σ_d W_d``, as CSR ``(n_in, n_out)``.

        Examples
        --------
        >>> import numpy as np
        >>> p = MatrixProjection(id="p", source="a", target="b", contract=("i",), produce=("o",),
        ...                      weights=np.array([[1.0, 2.0]]), delays=np.array([[0, 3]]))
        >>> {d: m.toarray().tolist() for d, m in p.by_delay().items()}
        {0: [[1.0, 0.0]], 3: [[0.0, 2.0]]}
        """
        if self.weights is not None:
            r, c = np.nonzero(self.weights)
            vals = self.weights[r, c]
            dl = self.delays[r, c] if self.delays is not None else np.zeros(r.size, np.int64)
        else:
            live = self.values != 0  # a stored zero is no synapse, as in the dense form
            r, c, vals = self.rows[live], self.cols[live], self.values[live]
            dl = self.delays[live] if self.delays is not None else np.zeros(r.size, np.int64)
        out = {}
        for d in np.unique(dl):
            m = dl == d
            out[int(d)] = sp.csr_matrix((vals[m], (r[m], c[m])), shape=self.n_in_out)
        return out or {0: sp.csr_matrix(self.n_in_out)}

    # ------------------------------------------------------------ projection protocol
    def stored_weights(self) -> np.ndarray:
        """The stored weight array: the dense ``(n_in, n_out)`` weights or the COO values.

        Examples
        --------
        >>> import numpy as np
        >>> MatrixProjection(id="p", source="a", target="b", contract=("i",), produce=("o",),
        ...                  rows=[0], cols=[1], values=[2.5], n_in_out=(1, 2)).stored_weights()
        array([2.5])
        """
        return self.weights if self.weights is not None else self.values

    def with_weights(self, w: np.ndarray) -> MatrixProjection:
        """This projection with its stored weight array (as :meth:`stored_weights`) replaced."""
        return replace(self, weights=w) if self.weights is not None else replace(self, values=w)

    def min_delay(self) -> int | None:
        """The smallest delay of a live (non-zero) synapse; ``None`` when no synapse is live.

        Examples
        --------
        >>> import numpy as np
        >>> MatrixProjection(id="p", source="a", target="b", contract=("i",), produce=("o",),
        ...                  weights=np.array([[0.0, 1.0]]), delays=np.array([[0, 2]])).min_delay()
        2
        """
        live = self.stored_weights() != 0
        if not live.any():
            return None
        return 0 if self.delays is None else int(self.delays[live].min())

    def repetitions(self, src: Population) -> int:
        """How many times the matrix is applied: :math:`R = |S| / n_{in}`."""
        return src.size // max(1, prod(src.shape[a] for a in self.contract))

    def repetition_axes(self, tgt: Population) -> set[str]:
        """The target axes the matrix is shared over (not in ``produce``)."""
        return {a for a in tgt.axes if a not in self.produce}

    def n_synapse_instances(self, src: Population, tgt: Population) -> int:
        r"""Nominal synapse instances :math:`R \cdot \mathrm{nnz}(W)` (the paper's count)."""
        return self.repetitions(src) * self.n_synapses

    def wired_synapses(self, src: Population, tgt: Population) -> int:
        """Distinct wired synapses over all repetitions: :math:`R` times the non-zero pattern."""
        return self.repetitions(src) * int(self.nonzero_pattern.nnz)

    @cached_property
    def nonzero_pattern(self) -> sp.csr_matrix:
        """Boolean ``(n_in, n_out)`` CSR pattern of the non-zero weights (computed once).

        Examples
        --------
        >>> import numpy as np
        >>> MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
        ...                  weights=np.array([[1.0, 0.0], [2.0, 3.0]])
        ...                  ).nonzero_pattern.toarray().tolist()
        [[True, False], [True, True]]
        """
        if self.weights is not None:
            return sp.csr_matrix(self.weights != 0)
        keep = self.values != 0
        m = sp.csr_matrix((np.ones(int(keep.sum()), bool), (self.rows[keep], self.cols[keep])),
                          shape=self.n_in_out)
        m.sum_duplicates()
        return m.astype(bool)

    def check_axes(self, src: Population, tgt: Population) -> None:
        """Raise :class:`~ir.errors.NetworkError` unless the axes and sizes fit ``src``/``tgt``."""
        pid = self.id
        for axes, pop, role in ((self.contract, src, "contract"), (self.produce, tgt, "produce")):
            missing = [a for a in axes if a not in pop.shape]
            if missing or len(set(axes)) != len(axes):
                raise NetworkError(f"projection {pid!r}: {role} axes {axes} must be distinct axes "
                                   f"of population {pop.id!r} (axes {pop.axes})", node=pid)
        n_in = prod(src.shape[a] for a in self.contract)
        n_out = prod(tgt.shape[a] for a in self.produce)
        if (n_in, n_out) != self.n_in_out:
            raise NetworkError(f"projection {pid!r}: matrix is {self.n_in_out} but the axes give "
                               f"({n_in}, {n_out})", node=pid)
        src_rep = {a: n for a, n in src.shape.items() if a not in self.contract}
        tgt_rep = {a: n for a, n in tgt.shape.items() if a not in self.produce}
        if src_rep != tgt_rep:
            raise NetworkError(f"projection {pid!r}: repetition axes differ: source {src.id!r} "
                               f"has {src_rep}, target {tgt.id!r} has {tgt_rep}", node=pid)
