"""Block rows of a :class:`~backends.reference.matrix.MatrixDelivery`: events in, targets out.

A matrix delivery computes its current as a block of shape ``(n_batch · n_reps, n_out)``:
one row per batch row and repetition, one column per produced output.  This module maps
source events onto those rows (:meth:`BlockRows.event_rows`) and adds rows into the
target's flat state in the target's axis order (:meth:`BlockRows.add_rows`, and
:meth:`BlockRows.add_paired_rows` for outputs split into ``(y, −y)`` parts); the block
layout itself is :func:`block_target_index`.

Examples
--------
>>> block_target_index((2, 3), (1, 0), 3).tolist()  # block (rep, out) read in (out, rep) order
[[0, 2, 4], [1, 3, 5]]
>>> block_target_index((2, 3), (0, 1), 3) is None  # the identity layout needs no map
True
"""

from __future__ import annotations

from functools import cached_property
from math import prod

import numpy as np
import scipy.sparse as sp

__all__ = ["BlockRows", "block_target_index"]


class BlockRows:
    """The row maps of :class:`~backends.reference.matrix.MatrixDelivery` (a mixin).

    Reads the delivery's ``rep_of``, ``col_of``, ``n_reps``, ``n_out``, ``weights`` and
    ``target_index`` fields.
    """

    def event_rows(self, events: np.ndarray, n_batch: int) -> tuple[np.ndarray, np.ndarray]:
        """The batch row ``b·n_reps + rep`` and the matrix row (``col_of``) of each event.

        Events are flat indices into ``(n_batch, *source_shape)``; with
        ``n_batch == 1`` no division is needed.

        Examples
        --------
        >>> import numpy as np
        >>> from backends.reference.matrix import MatrixDelivery
        >>> from compiler.snn import MatrixProjection, Population
        >>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",),
        ...                      produce=("o",), weights=np.ones((2, 1)))
        >>> a = Population(id="a", shape={"i": 2, "r": 3}, source=True)
        >>> d = MatrixDelivery.build(p, a, Population(id="b", shape={"r": 3, "o": 1}))
        >>> [a.tolist() for a in d.event_rows(np.array([1, 3, 6]), n_batch=2)]
        [[1, 0, 3], [0, 1, 0]]
        """
        if n_batch == 1:
            return self.rep_of[events], self.col_of[events]
        b, n = np.divmod(events, self.col_of.size)
        return b * self.n_reps + self.rep_of[n], self.col_of[n]

    def add_rows(self, hit: np.ndarray, part: np.ndarray, out: np.ndarray) -> None:
        """``out[target of row r] += part[r]`` for the (distinct) block rows ``hit``, in place."""
        if self.target_index is None:  # blocks are already in target order
            out.reshape(-1, self.n_out)[hit] += part
        else:
            b, rep = np.divmod(hit, self.n_reps)
            out[(b * (self.n_reps * self.n_out))[:, None] + self.target_index[rep]] += part

    @cached_property
    def paired_halves(self) -> tuple[np.ndarray | None, ...]:
        """Per delay class, ``W[:, 0::2]`` (contiguous) when ``W[:, 1::2] == −W[:, 0::2]``
        — an output split into ``(y, −y)`` parts — else None (built on first use).

        A sum of such rows is then the sum of their even halves ``h`` and its negation,
        bit for bit (negation commutes with every rounding); :meth:`add_paired_rows`
        adds ``h`` and subtracts it (``u − h = u + (−h)``, and ``u`` is never ``−0``
        where it starts at ``+0`` and gains sums).  Gathering the half rows moves half
        the bytes from a table half the size.
        """
        out = []
        for w in self.weights:
            even = None
            if not sp.issparse(w) and w.ndim == 2 and w.shape[1] >= 2 and w.shape[1] % 2 == 0:
                half = w[:, 0::2]
                if np.array_equal(w[:, 1::2], -half):
                    even = np.ascontiguousarray(half)
            out.append(even)
        return tuple(out)

    def add_paired_rows(self, hit: np.ndarray, half: np.ndarray, out: np.ndarray) -> None:
        """:meth:`add_rows` of the rows ``(h_0, −h_0, h_1, −h_1, …)`` given ``half = h``."""
        if self.target_index is None:
            pairs = out.reshape(-1, self.n_out // 2, 2)
            pairs[hit, :, 0] += half
            pairs[hit, :, 1] -= half
        else:
            b, rep = np.divmod(hit, self.n_reps)
            index = (b * (self.n_reps * self.n_out))[:, None] + self.target_index[rep]
            out[index[:, 0::2]] += half
            out[index[:, 1::2]] -= half


def block_target_index(
    block_shape: tuple[int, ...], to_target: tuple[int, ...], n_out: int
) -> np.ndarray | None:
    """Flat target index of each ``(rep, out)`` block entry; None for the identity layout."""
    if to_target == tuple(range(len(to_target))):
        return None
    size = prod(block_shape)
    # the block transposed into target order, read in target (C) order, is block index by
    # target position: invert it
    block_of_target = np.arange(size).reshape(block_shape).transpose(to_target).reshape(-1)
    index = np.empty(size, np.int64)
    index[block_of_target] = np.arange(size)
    return index.reshape(-1, n_out)
