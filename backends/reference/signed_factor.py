r"""Sign-symmetric structure of a weight matrix, for a cheaper dense product.

The signed and complex latency splits put a value ``x`` on the parts ``x⁺, x⁻`` (and
``Re, Im``) of a trailing ``part`` axis; a linear motif then has weights
``(w, −w)`` on the two parts of an input and produces ``(y, −y)`` on the two parts
of an output.  :func:`signed_factor` finds that structure in any dense matrix:

.. math:: W = P_{in}^{\top}\, W_c\, P_{out}, \qquad
          P_{in}[c, i] = s_i\,[c_i = c], \quad P_{out}[c, j] = \sigma_j\,[d_j = c]

with signs :math:`s_i, \sigma_j \in \{-1, 0, +1\}` (0 for an all-zero row or column)
and :math:`W_c` the distinct rows and columns up to sign.  Then
:math:`E W = ((E P_{in}^{\top}) W_c) P_{out}`: the one-hot events are folded onto
the core rows with their signs, one BLAS product with the (up to 4× smaller)
core, and the columns are copied out with their signs.  Every step but the core
product is exact, so the result equals ``E @ W`` whenever the sums are exact
(the closed form's guarantee); otherwise it may differ in the last bits.

Examples
--------
>>> import numpy as np
>>> w = np.array([[1.0, -1.0], [-1.0, 1.0], [2.0, -2.0]])
>>> f = signed_factor(w)
>>> f.core.tolist(), f.in_row.tolist(), f.in_sign.tolist(), f.out_sign.tolist()
([[1.0], [2.0]], [0, 0, 1], [1.0, -1.0, 1.0], [1.0, -1.0])
>>> bool(np.all(f.in_sign[:, None] * f.core[f.in_row][:, f.out_col] * f.out_sign == w))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SignedFactor", "distinct_up_to_sign", "signed_factor"]


@dataclass(frozen=True, eq=False)
class SignedFactor:
    """``W[i, j] = in_sign[i] · core[in_row[i], out_col[j]] · out_sign[j]``."""

    core: np.ndarray
    in_row: np.ndarray
    in_sign: np.ndarray
    out_col: np.ndarray
    out_sign: np.ndarray

    @property
    def saving(self) -> float:
        """Core size over full size (the fraction of multiply-adds left)."""
        return self.core.size / max(1, self.in_row.size * self.out_col.size)


def _fold_rows(w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distinct rows of ``w`` up to the sign of their first non-zero entry (exact: ``±w``)."""
    nonzero = w != 0
    first = nonzero.argmax(axis=1)
    sign = np.sign(w[np.arange(w.shape[0]), first])  # 0 for an all-zero row
    canon = w * np.where(sign != 0, sign, 1.0)[:, None]
    core, inverse = np.unique(canon, axis=0, return_inverse=True)
    return core, inverse.reshape(-1).astype(np.int64), sign.astype(np.float64)


def distinct_up_to_sign(w: np.ndarray) -> tuple[int, int]:
    """Upper bounds on the distinct rows and columns of ``w`` up to sign, in two mat-vecs.

    Rows equal up to sign have equal ``|w·r|`` for any vector ``r``; the count of
    distinct ``|w·r|`` (``r`` fixed pseudo-random) can only over-count, so it is a
    cheap test of whether :func:`signed_factor` is worth its sort.

    Examples
    --------
    >>> distinct_up_to_sign(np.array([[1.0, -1.0], [-1.0, 1.0], [2.0, -2.0]]))
    (2, 1)
    """
    w = np.asarray(w, dtype=np.float64)
    rng = np.random.default_rng(12345)
    rows = np.unique(np.abs(w @ rng.standard_normal(w.shape[1]))).size
    cols = np.unique(np.abs(rng.standard_normal(w.shape[0]) @ w)).size
    return rows, cols


def signed_factor(w: np.ndarray) -> SignedFactor:
    """Factor a dense float matrix into distinct rows/columns up to a scalar (see module doc).

    Rows equal up to sign share one core row; the same for columns.  An
    all-zero row or column gets sign 0.
    """
    rows, in_row, in_scale = _fold_rows(np.asarray(w, dtype=np.float64))
    cols, out_col, out_scale = _fold_rows(rows.T)
    return SignedFactor(core=np.ascontiguousarray(cols.T), in_row=in_row, in_sign=in_scale,
                        out_col=out_col, out_sign=out_scale)
