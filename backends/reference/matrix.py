r"""Delivery of a :class:`~compiler.snn.MatrixProjection`: one shared matrix along named axes.

Source events (flat indices into ``(n_batch, *source_shape)``) become a sparse
one-hot matrix ``E`` of shape ``(rows hit, n_in)`` — row = batch × repetition,
column = the flattened ``contract`` index — and the current is

.. math:: I = E\,W_k \quad\text{reshaped to } (n_{batch}, \text{reps}, \text{produce})
          \text{ and permuted into the target's axis order,}

an event-driven product that reads only the weight rows of spiking inputs;
each output sums its rows in ascending column order.  ``W`` is stored once per
delay class (a dense projection without delays keeps its own array), never
tiled over repetitions; repetition axes are matched by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import prod

import numpy as np
import scipy.sparse as sp

from backends.reference.signed_factor import SignedFactor, distinct_up_to_sign, signed_factor
from compiler.snn.network import Population
from compiler.snn.projections import MatrixProjection

#: Above ``n_in / 16`` weighted events per target row the one-hot BLAS product beats gathering.
_DENSE_EVENTS_PER_ROW = 16

__all__ = ["MatrixDelivery"]

#: Factor dense matrices of at least this many entries (smaller ones are cheap anyway).
_FACTOR_MIN_ENTRIES = 4096


def _worth_factoring(w, integer: bool) -> SignedFactor | None:
    """The sign-symmetric factor of a large dense float ``w`` if it halves the work, else None."""
    if integer or sp.issparse(w) or w.size < _FACTOR_MIN_ENTRIES:
        return None
    rows, cols = distinct_up_to_sign(w)  # two mat-vecs: skip the sort when it cannot pay
    if rows * cols > 0.5 * w.size:
        return None
    factor = signed_factor(w)
    return factor if factor.saving <= 0.5 else None


@dataclass(frozen=True, eq=False)
class MatrixDelivery:
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
        factors = tuple(_worth_factoring(w, integer) for w in weights)
        return cls(
            id=proj.id, source=proj.source, target=proj.target, delays=delays, weights=weights,
            row_synapses=row_synapses, rep_of=rep_of.astype(np.int64),
            col_of=col_of.astype(np.int64), n_reps=prod(rep_dims), n_in=proj.n_in,
            n_out=proj.n_out, block_shape=rep_dims + tuple(tgt.shape[a] for a in proj.produce),
            to_target=tuple(block_axes.index(a) for a in tgt.axes), integer=integer,
            factors=factors,
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
        n_src = self.col_of.size
        b, n = np.divmod(events, n_src)
        rows = b * self.n_reps + self.rep_of[n]
        dtype = np.int64 if self.integer else np.float64
        weights = self.weights[k]
        if sp.issparse(weights):
            hit, local = np.unique(rows, return_inverse=True)
            data = np.ones(events.size, dtype) if values is None else values.astype(dtype)
            one_hot = sp.csr_matrix((data, (local.ravel(), self.col_of[n])),
                                    shape=(hit.size, self.n_in))
            one_hot.sum_duplicates()
            part = (one_hot @ weights).toarray()
        elif ((values is not None or self.blas_events) and not self.integer
              and events.size * _DENSE_EVENTS_PER_ROW >= n_batch * self.n_reps * self.n_in):
            # dense over the whole batch (the closed form's silent stage): one-hot over every
            # row by one bincount (events added in order), one BLAS product, no sorting
            n_rows = n_batch * self.n_reps
            data = None if values is None else values.astype(dtype)
            factor = self.factors[k] if self.factors else None
            if factor is not None:  # fold ±-symmetric parts first: a smaller core product
                cols = self.col_of[n]
                signed = factor.in_sign[cols] if data is None else data * factor.in_sign[cols]
                n_core = factor.core.shape[0]
                one_hot = np.bincount(rows * n_core + factor.in_row[cols], weights=signed,
                                      minlength=n_rows * n_core).reshape(n_rows, n_core)
                product = (one_hot @ factor.core)[:, factor.out_col] * factor.out_sign
            else:
                one_hot = np.bincount(rows * self.n_in + self.col_of[n], weights=data,
                                      minlength=n_rows * self.n_in).reshape(n_rows, self.n_in)
                product = one_hot @ weights
            block = product.astype(dtype, copy=False).reshape(n_batch, *self.block_shape)
            return block.transpose(0, *(1 + a for a in self.to_target))
        else:
            order = np.argsort(rows, kind="stable")
            rows, cols = rows[order], self.col_of[n[order]]
            starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]]) if rows.size else rows
            hit = rows[starts]
            data = None if values is None else values[order].astype(dtype)
            blas = data is not None or self.blas_events
            if blas and events.size * _DENSE_EVENTS_PER_ROW >= hit.size * self.n_in:
                # dense: a one-hot block and one BLAS product.  Only for the closed form's
                # weighted features, or networks the closed form cannot run: otherwise the
                # step engine and the closed form's driven path both gather, adding every
                # row's weights in the same order, bit for bit.
                local = np.repeat(np.arange(hit.size), np.diff(np.r_[starts, rows.size]))
                if self.integer:
                    one_hot = np.zeros((hit.size, self.n_in), dtype)
                    np.add.at(one_hot, (local, cols), 1 if data is None else data)
                else:  # bincount adds in event order, like add.at, but much faster
                    one_hot = np.bincount(local * self.n_in + cols, weights=data,
                                          minlength=hit.size * self.n_in)
                    one_hot = one_hot.reshape(hit.size, self.n_in)
                part = one_hot @ weights
            else:  # sparse in time: gather each event's weight row, add them per target row
                gathered = weights[cols]
                if data is not None:
                    gathered = gathered * data[:, None]
                part = np.add.reduceat(gathered, starts, axis=0) if rows.size else gathered
        full = np.zeros((n_batch * self.n_reps, self.n_out), dtype)
        full[hit] = part
        block = full.reshape(n_batch, *self.block_shape)
        return block.transpose(0, *(1 + a for a in self.to_target))

    def n_events(self, k: int, events: np.ndarray) -> int:
        """Synaptic events of the events of delay class ``k`` (spikes × synapses reached)."""
        n = events % self.col_of.size
        return int(self.row_synapses[k][self.col_of[n]].sum())
