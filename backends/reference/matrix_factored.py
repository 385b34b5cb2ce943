"""The sign-symmetric factored product of a :class:`~backends.reference.matrix.MatrixDelivery`.

A dense float matrix whose rows and columns repeat up to sign (a DFT's cosines and sines)
is stored with its :class:`~backends.reference.signed_factor.SignedFactor`: the events'
one-hot block is folded onto the core's rows, multiplied by the smaller core, and the
core's columns are spread back with their signs.  :func:`worth_factoring` decides when
a matrix gets a factor; :class:`FactoredProduct` holds the products of the dense
whole-batch path (the closed form's silent stage and weighted features).

Examples
--------
>>> import numpy as np
>>> worth_factoring(np.ones((4, 4)), integer=False) is None  # small: not worth it
True
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from backends.reference.signed_factor import SignedFactor, distinct_up_to_sign, signed_factor

__all__ = ["DENSE_EVENTS_PER_ROW", "FACTOR_MIN_ENTRIES", "FactoredProduct", "worth_factoring"]

#: Above ``n_in / 16`` weighted events per target row the one-hot BLAS product beats gathering.
DENSE_EVENTS_PER_ROW = 16

#: Factor dense matrices of at least this many entries (smaller ones are cheap anyway).
FACTOR_MIN_ENTRIES = 4096


def worth_factoring(w, integer: bool) -> SignedFactor | None:
    """The sign-symmetric factor of a large dense float ``w`` if it halves the work, else None."""
    if integer or sp.issparse(w) or w.size < FACTOR_MIN_ENTRIES:
        return None
    rows, cols = distinct_up_to_sign(w)  # two mat-vecs: skip the sort when it cannot pay
    if rows * cols > 0.5 * w.size:
        return None
    factor = signed_factor(w)
    return factor if factor.saving <= 0.5 else None


class FactoredProduct:
    """The factored dense products of :class:`~backends.reference.matrix.MatrixDelivery`
    (a mixin).

    Reads the delivery's ``factors``, ``factor_slots``, ``weights``, ``integer``,
    ``col_of``, ``n_reps``, ``n_in``, ``n_out``, ``block_shape``, ``to_target`` and
    ``target_index`` fields.
    """

    def _folded_product(self, k: int, events: np.ndarray, n_batch: int,
                        values: np.ndarray | None) -> np.ndarray:
        """The dense whole-batch product through the sign-symmetric factor of class ``k``.

        The ±-symmetric input rows are folded first (one bincount onto the core's rows,
        signs applied, events added in order), then one smaller BLAS product with the
        core, whose columns are spread back with their signs.
        """
        factor, (slot, sign) = self.factors[k], self.factor_slots[k]
        n_core = factor.core.shape[0]
        if n_batch == 1:
            index, signed = slot[events], sign[events]
        else:
            b, n = np.divmod(events, self.col_of.size)
            index, signed = b * (self.n_reps * n_core) + slot[n], sign[n]
        if values is not None:
            signed = signed * values
        one_hot = np.bincount(index, weights=signed, minlength=n_batch * self.n_reps * n_core)
        product = one_hot.reshape(-1, n_core) @ factor.core
        out = np.take(product, factor.out_col, axis=1)
        out *= factor.out_sign
        return out

    def dense_for(self, k: int, n_events: int | None, n_batch: int) -> bool:
        """Whether :meth:`feature_current` serves weighted events of class ``k`` (the
        folded whole-batch product :meth:`current` itself takes for ``n_events`` of them;
        ``None``: whether it could for some count)."""
        if self.integer or sp.issparse(self.weights[k]) or self.factors[k] is None:
            return False
        return n_events is None or n_events * DENSE_EVENTS_PER_ROW >= (
            n_batch * self.n_reps * self.n_in)

    def feature_current(self, k: int, feature: np.ndarray, n_batch: int) -> np.ndarray:
        """:meth:`current` of weighted events given as a dense per-source ``feature``.

        ``feature`` (float64, ``n_batch × source size``) holds each source neuron's event
        value, 0 for none: the one-hot fold is then one sparse product with the fixed fold
        of source neurons onto the core's rows (:attr:`_folds`), no event gathers.  In the
        closed form the values are whole numbers and the fold's sums exact, so the result
        equals :meth:`current`'s bit for bit (:meth:`dense_for` must hold).

        Examples
        --------
        >>> import numpy as np
        >>> from backends.reference.matrix import MatrixDelivery
        >>> from compiler.snn import MatrixProjection, Population
        >>> n = 64  # a cosine matrix: rows and columns equal up to sign fold to 33 × 33
        >>> w = np.round(256 * np.cos(2 * np.pi * np.outer(np.arange(n), np.arange(n)) / n)) / 256
        >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
        ...                      produce=("o",), weights=w)
        >>> d = MatrixDelivery.build(p, Population(id="a", shape={"i": n}, source=True),
        ...                          Population(id="b", shape={"o": n}))
        >>> events, values = np.array([1, 5, 40, 63]), np.array([3.0, 1.0, 2.0, 4.0])
        >>> feature = np.zeros(n)
        >>> feature[events] = values
        >>> ref = d.current(0, events, 1, values=values)
        >>> out = d.feature_current(0, feature, 1)
        >>> d.dense_for(0, events.size, 1), bool(np.array_equal(out, ref))
        (True, True)
        """
        factor, fold = self.factors[k], self._folds[k]
        n_core = factor.core.shape[0]
        if n_batch == 1:
            one_hot = fold @ feature
        else:
            one_hot = (fold @ feature.reshape(n_batch, -1).T).T
        product = (one_hot.reshape(-1, n_core) @ factor.core).reshape(n_batch, -1)
        spread, sign = self._spreads[k]
        # the core's columns spread to the target's neurons in target order, with their signs
        out = np.take(product, spread, axis=1)
        out *= sign
        return out.reshape(n_batch, *(self.block_shape[a] for a in self.to_target))

    @cached_property
    def _spreads(self) -> tuple[tuple[np.ndarray, np.ndarray] | None, ...]:
        """Per class with a factor: for each target neuron (target order) its entry of the
        ``(n_reps, core columns)`` product and its sign (built on first use)."""
        out = []
        for factor in self.factors:
            if factor is None:
                out.append(None)
                continue
            size = self.n_reps * self.n_out
            entry = (np.arange(size) if self.target_index is None
                     else np.argsort(self.target_index.ravel()))  # block entry per target
            rep, col = np.divmod(entry, self.n_out)
            out.append((rep * factor.core.shape[1] + factor.out_col[col],
                        factor.out_sign[col]))
        return tuple(out)

    @cached_property
    def _folds(self) -> tuple[sp.csr_matrix | None, ...]:
        """Per class with a factor: the fold of source neurons onto the core's rows.

        A ``(n_reps · core rows) × source size`` CSR of the signs (one entry per source
        neuron whose row is not zero), so ``fold @ feature`` is the one-hot fold of
        :meth:`_folded_product`; built on first use.
        """
        folds = []
        for factor, slots in zip(self.factors, self.factor_slots, strict=True):
            if factor is None:
                folds.append(None)
                continue
            slot, sign = slots
            keep = np.flatnonzero(sign != 0)
            fold = sp.csr_matrix((sign[keep], (slot[keep], keep)),
                                 shape=(self.n_reps * factor.core.shape[0], slot.size))
            fold.sort_indices()
            folds.append(fold)
        return tuple(folds)
