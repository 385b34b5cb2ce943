r"""Delivery of a :class:`~compiler.snn.MatrixProjection`: one shared matrix along named axes.

Source events (flat indices into ``(n_batch, *source_shape)``) become a sparse
one-hot matrix ``E`` of shape ``(rows hit, n_in)`` — row = batch × repetition,
column = the flattened ``contract`` index — and the current is

.. math:: I = E\,W_k \quad\text{reshaped to } (n_{batch}, \text{reps}, \text{produce})
          \text{ and permuted into the target's axis order,}

an event-driven product that reads only the weight rows of spiking inputs.
``W`` is stored once per delay class (a dense projection without delays keeps
its own array), never tiled over repetitions; repetition axes are matched by name.

The gathering path's arithmetic (shared by both engines for unweighted events) is
:mod:`backends.reference.row_sums`'s; the block's row maps are in
:mod:`~backends.reference.matrix_rows`, the factored dense product of sign-symmetric
matrices in :mod:`~backends.reference.matrix_factored` and the synaptic-event counts in
:mod:`~backends.reference.matrix_counts`.
:meth:`MatrixDelivery.add_to` adds the current into a flat state array touching
only the rows hit.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import prod

import numpy as np
import scipy.sparse as sp

from backends.reference.matrix_counts import MAX_FANOUT_GROUPS, SynapseCounts
from backends.reference.matrix_factored import (
    DENSE_EVENTS_PER_ROW,
    FactoredProduct,
    worth_factoring,
)
from backends.reference.matrix_rows import BlockRows, block_target_index
from backends.reference.row_sums import distinct_rows, grouped_sums, n_runs, run_starts
from backends.reference.signed_factor import SignedFactor
from compiler.snn.network import Population
from compiler.snn.projections import MatrixProjection

__all__ = ["MAX_FANOUT_GROUPS", "MatrixDelivery"]


@dataclass(frozen=True, eq=False)
class MatrixDelivery(BlockRows, FactoredProduct, SynapseCounts):
    """The delivery plan of one :class:`~compiler.snn.MatrixProjection`.

    Attributes
    ----------
    id, source, target : str
        Projection and population ids.
    delays : tuple of int
        The delay classes, ascending.
    weights : tuple
        ``W_k`` per delay class, ``(n_in, n_out)``: a dense ndarray or CSR.
    row_synapses : tuple of ndarray
        Non-zero weights per matrix row, per delay class.
    rep_of, col_of : ndarray
        Per flat source neuron: its repetition index (in the target's axis
        order) and its matrix row.
    n_reps : int
        Repetitions sharing the weights.
    block_shape, to_target : tuple of int
        ``E @ W`` reshaped to ``(batch, *block_shape)`` (repetition axes in target
        order, then ``produce``) is permuted by ``to_target`` into target order.
    """

    id: str
    source: str
    target: str
    delays: tuple[int, ...]
    weights: tuple[np.ndarray | sp.csr_matrix, ...]
    row_synapses: tuple[np.ndarray, ...]
    rep_of: np.ndarray
    col_of: np.ndarray
    n_reps: int
    n_in: int
    n_out: int
    block_shape: tuple[int, ...]
    to_target: tuple[int, ...]
    integer: bool
    #: Let unweighted events take the BLAS path when dense (set by ``build_plan`` for networks
    #: the closed form cannot run, where no second engine must add in the same order).
    blas_events: bool = False
    #: Per delay class, the sign-symmetric factor of a dense float matrix when it saves at
    #: least half the multiply-adds of the dense whole-batch product (else None).
    factors: tuple[SignedFactor | None, ...] = ()
    #: Per delay class with a factor, per source neuron: its slot ``rep·n_core + in_row`` in
    #: the folded one-hot block of one batch row, and its ``in_sign`` (else None).
    factor_slots: tuple[tuple[np.ndarray, np.ndarray] | None, ...] = ()
    #: ``(n_reps, n_out)`` flat target index (within one batch row) of each block entry, or
    #: None when the block order is the target order (repetition axes first, then produce).
    target_index: np.ndarray | None = None
    #: Per delay class, the synapses of each source neuron (int64, source size).
    source_synapses: tuple[np.ndarray, ...] = ()

    @classmethod
    def build(
        cls, proj: MatrixProjection, src: Population, tgt: Population, integer: bool = False
    ) -> MatrixDelivery:
        """Precompute the index maps and weight operands of ``proj``.

        Parameters
        ----------
        proj : MatrixProjection
        src, tgt : Population
            Its source and target (already validated against it).
        integer : bool
            Store int64 weights (the caller checked they are whole numbers).

        Returns
        -------
        MatrixDelivery

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import MatrixProjection, Population
        >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
        ...                      produce=("o",), weights=np.eye(2))
        >>> a = Population(id="a", shape={"r": 3, "i": 2}, source=True)
        >>> b = Population(id="b", shape={"o": 2, "r": 3})
        >>> d = MatrixDelivery.build(p, a, b)
        >>> d.weights[0] is p.weights, d.n_reps, d.current(0, np.array([1]), 1)[0].tolist()
        (True, 3, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
        """
        dtype = np.int64 if integer else np.float64
        if proj.weights is not None and proj.delays is None:
            w = proj.weights if not integer else proj.weights.astype(np.int64)
            classes = {0: w}
        else:
            classes = {d: m.astype(dtype) for d, m in proj.by_delay().items()}
        delays = tuple(sorted(classes))
        weights = tuple(classes[d] for d in delays)
        row_synapses = tuple(
            np.diff(w.indptr) if sp.issparse(w) else np.count_nonzero(w, axis=1) for w in weights
        )
        rep_axes = tuple(a for a in tgt.axes if a not in proj.produce)
        grid = np.indices(src.dims).reshape(len(src.dims), -1)
        coord = dict(zip(src.axes, grid, strict=True))
        rep_dims = tuple(tgt.shape[a] for a in rep_axes)
        rep_of = (np.ravel_multi_index(tuple(coord[a] for a in rep_axes), rep_dims)
                  if rep_axes else np.zeros(src.size, np.int64))
        col_of = (np.ravel_multi_index(tuple(coord[a] for a in proj.contract),
                                       tuple(src.shape[a] for a in proj.contract))
                  if proj.contract else np.zeros(src.size, np.int64))
        block_axes = rep_axes + proj.produce
        factors = tuple(worth_factoring(w, integer) for w in weights)
        to_target = tuple(block_axes.index(a) for a in tgt.axes)
        block_shape = rep_dims + tuple(tgt.shape[a] for a in proj.produce)
        return cls(
            id=proj.id, source=proj.source, target=proj.target, delays=delays, weights=weights,
            row_synapses=row_synapses, rep_of=rep_of.astype(np.int64),
            col_of=col_of.astype(np.int64), n_reps=prod(rep_dims), n_in=proj.n_in,
            n_out=proj.n_out, block_shape=block_shape, to_target=to_target, integer=integer,
            factors=factors, target_index=block_target_index(block_shape, to_target, proj.n_out),
            factor_slots=tuple(None if f is None else (
                (rep_of * f.core.shape[0] + f.in_row[col_of]).astype(np.int64),
                f.in_sign[col_of]) for f in factors),
            source_synapses=tuple(r[col_of].astype(np.int64) for r in row_synapses),
        )

    @property
    def src_size(self) -> int:
        """Neurons in the source population."""
        return self.col_of.size

    @property
    def weight_nbytes(self) -> int:
        """Bytes held by the weight operands (independent of the repetition count)."""
        return sum(w.nbytes if not sp.issparse(w) else
                   w.data.nbytes + w.indices.nbytes + w.indptr.nbytes for w in self.weights)

    def current(
        self, k: int, events: np.ndarray, n_batch: int, values: np.ndarray | None = None
    ) -> np.ndarray:
        """The current of the events of delay class ``k``: ``(n_batch, *target_shape)``.

        ``values`` (default 1 per event) scales each event, which the closed form
        uses to weight arrivals by their remaining steps.
        """
        dtype = np.int64 if self.integer else np.float64
        hit, part = self._row_sums(k, events, n_batch, values)
        if hit is None:  # the whole batch came out dense
            block = part
        else:
            full = np.zeros((n_batch * self.n_reps, self.n_out), dtype)
            full[hit] = part
            block = full
        block = block.reshape(n_batch, *self.block_shape)
        return block.transpose(0, *(1 + a for a in self.to_target))

    def add_to(self, k: int, events: np.ndarray, n_batch: int, out: np.ndarray) -> None:
        """``out += current(k, events, n_batch)`` in place, touching only the rows hit.

        ``out`` is the flat ``(n_batch * target size)`` array of the target (the
        delivery's dtype).  Where ``out`` holds no negative zero the result is
        bit-identical to ``out + current(...)`` (adding ``+0.0`` to the rows not
        hit changes nothing else).

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import MatrixProjection, Population
        >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
        ...                      produce=("o",), weights=np.array([[1.0, 2.0], [4.0, 8.0]]))
        >>> a = Population(id="a", shape={"r": 2, "i": 2}, source=True)
        >>> d = MatrixDelivery.build(p, a, Population(id="b", shape={"o": 2, "r": 2}))
        >>> out = np.full(4, 0.5)
        >>> d.add_to(0, np.array([2, 3]), 1, out)  # rep 1, both inputs: 1 + 4, 2 + 8
        >>> out.tolist()
        [0.5, 5.5, 0.5, 10.5]
        """
        hit, part = self._row_sums(k, events, n_batch, None)
        if hit is None:
            block = part.reshape(n_batch, *self.block_shape)
            out += block.transpose(0, *(1 + a for a in self.to_target)).reshape(-1)
        else:
            self.add_rows(hit, part, out)

    @property
    def rows_independent(self) -> bool:
        """Whether a batch row's current depends on that row's events alone.

        True for the gathering path (dense weights, no BLAS one-hot products):
        then the currents of many steps can be computed in one batch, bit for bit
        as step by step (:class:`~backends.reference.delivery.TrainCurrents`).
        """
        return not self.blas_events and not any(sp.issparse(w) for w in self.weights)

    def row_currents(self, k: int, events: np.ndarray, n_batch: int,
                     workspace: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(rows hit, their (rows, n_out) currents)`` of unweighted events (``rows_independent``).

        ``workspace`` (``(≥ events, n_out)``, the delivery's dtype) is gathered
        into when given (see :func:`grouped_sums`); the currents may then be a view of it.

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import MatrixProjection, Population
        >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
        ...                      produce=("o",), weights=np.array([[1.0, 2.0], [4.0, 8.0]]))
        >>> d = MatrixDelivery.build(p, Population(id="a", shape={"i": 2}, source=True),
        ...                          Population(id="b", shape={"o": 2}))
        >>> [a.tolist() for a in d.row_currents(0, np.array([0, 1, 3]), 2)]
        [[0, 1], [[5.0, 10.0], [4.0, 8.0]]]
        """
        hit, part = self._row_sums(k, events, n_batch, None, workspace)
        if hit is None:  # not rows_independent: dense block
            return np.arange(part.shape[0]), part
        return hit, part

    def _row_sums(
        self, k: int, events: np.ndarray, n_batch: int, values: np.ndarray | None,
        workspace: np.ndarray | None = None,
    ) -> tuple[np.ndarray | None, np.ndarray]:
        """``(hit rows, their currents)``, or ``(None, dense (rows, n_out) block)``."""
        dtype = np.int64 if self.integer else np.float64
        weights = self.weights[k]
        dense = ((values is not None or self.blas_events) and not self.integer
                 and events.size * DENSE_EVENTS_PER_ROW >= n_batch * self.n_reps * self.n_in)
        if dense and not sp.issparse(weights) and self.factors and self.factors[k] is not None:
            return None, self._folded_product(k, events, n_batch, values)
        rows, cols = self.event_rows(events, n_batch)
        if sp.issparse(weights):
            hit, local = distinct_rows(rows, n_batch * self.n_reps)
            data = np.ones(events.size, dtype) if values is None else values.astype(dtype)
            one_hot = sp.csr_matrix((data, (local, cols)), shape=(hit.size, self.n_in))
            one_hot.sum_duplicates()
            return hit, (one_hot @ weights).toarray()
        if dense:
            # dense over the whole batch (the closed form's silent stage): one-hot over every
            # row by one bincount (events added in order), one BLAS product, no sorting
            n_rows = n_batch * self.n_reps
            data = None if values is None else values.astype(dtype)
            one_hot = np.bincount(rows * self.n_in + cols, weights=data,
                                  minlength=n_rows * self.n_in).reshape(n_rows, self.n_in)
            return None, (one_hot @ weights).astype(dtype, copy=False)
        if rows.size > 1 and (rows[1:] < rows[:-1]).any():
            order = np.argsort(rows, kind="stable")
            rows, cols = rows[order], cols[order]
            values = None if values is None else values[order]
        data = None if values is None else values.astype(dtype)
        blas = data is not None or self.blas_events
        if blas and events.size * DENSE_EVENTS_PER_ROW >= self.n_in * n_runs(rows):
            # dense: a one-hot block and one BLAS product.  Only for the closed form's
            # weighted features, or networks the closed form cannot run: otherwise the
            # step engine and the closed form's driven path both gather, adding every
            # row's weights in the same order, bit for bit.
            starts = run_starts(rows)
            hit = rows[starts]
            local = np.repeat(np.arange(hit.size), np.diff(np.append(starts, rows.size)))
            if self.integer:
                one_hot = np.zeros((hit.size, self.n_in), dtype)
                np.add.at(one_hot, (local, cols), 1 if data is None else data)
            else:  # bincount adds in event order, like add.at, but much faster
                one_hot = np.bincount(local * self.n_in + cols, weights=data,
                                      minlength=hit.size * self.n_in)
                one_hot = one_hot.reshape(hit.size, self.n_in)
            return hit, one_hot @ weights
        # sparse in time: gather each event's weight row, add them per target row
        return grouped_sums(weights, cols, rows, data, workspace)
