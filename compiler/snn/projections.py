r"""Projections: how spikes of one population become input current of another.

Populations are tensors of neurons with **named axes** (e.g. ``rx, chirp,
sample``).  A projection acts on some axes and is *shared* over all the
others, which is how one motif is instantiated for every chirp and receiver
while its weights are stored once:

:class:`MatrixProjection`
    contracts the source axes ``contract`` (flattened in the order given)
    into the target axes ``produce`` with one matrix ``W`` of shape
    ``(n_in, n_out)``.  The remaining axes — the *repetition* axes — must
    appear in both populations with the same sizes (any order: the Doppler
    DFT consumes the range DFT's output transposed).  Weights are dense or
    sparse (COO), with optional per-synapse integer delays.
:class:`StencilProjection`
    one kernel correlated over the map axes ``axes`` of a source and a target
    of the same shape (CFAR windows): ``I[x] = Σ_o K[o] s[x + o]``, offsets
    ``o`` centred on the kernel middle, ``wrap`` or ``clip`` (no synapse)
    beyond the map per axis; optional per-tap delays.  Source and target have
    the same axes and sizes, matched by name (their memory order may differ).

A spike emitted at step ``t`` through a synapse of delay ``d`` enters the
target's ``I[t + d]``.  ``d = 0`` delivers in the same step (the simulator
processes populations in order of zero-delay edges, so a zero-delay cycle is
an error).

Examples
--------
>>> import numpy as np
>>> p = MatrixProjection(id="dft", source="x", target="y", contract=("sample",),
...                      produce=("range",), weights=np.eye(4))
>>> p.n_synapses, p.n_in, p.n_out
(4, 4, 4)
>>> k = StencilProjection(id="cfar", source="x", target="y", axes=("range",),
...                       kernel=np.array([-1.0, 0.0, 2.0, 0.0, -1.0]), edge=("wrap",))
>>> k.n_taps, k.radius
(3, (2,))
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Literal

import numpy as np
import scipy.sparse as sp

from ir.errors import NetworkError

__all__ = ["MatrixProjection", "StencilProjection", "Projection", "EdgeMode", "weights_of",
           "with_weights"]

EdgeMode = Literal["wrap", "clip"]


def _int_delays(delays: np.ndarray | None, shape: tuple[int, ...], pid: str) -> np.ndarray | None:
    if delays is None:
        return None
    d = np.asarray(delays)
    if d.shape != shape:
        raise NetworkError(
            f"projection {pid!r}: delays have shape {d.shape}, expected {shape} (one per synapse)",
            node=pid,
        )
    if d.size and (not np.issubdtype(d.dtype, np.integer) or d.min() < 0):
        raise NetworkError(
            f"projection {pid!r}: delays must be non-negative integers (steps), got dtype "
            f"{d.dtype} and minimum {d.min() if d.size else 'n/a'}",
            node=pid,
        )
    d = d.astype(np.int64)
    return None if not d.any() else d


def _finite_weights(w: np.ndarray, pid: str) -> np.ndarray:
    w = np.asarray(w, dtype=np.float64)
    if not np.all(np.isfinite(w)):
        raise NetworkError(f"projection {pid!r}: weights contain NaN or Inf", node=pid)
    return w


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


@dataclass(frozen=True, eq=False)
class StencilProjection:
    """One kernel correlated over map axes: ``I[x] = Σ_o K[o] · s[x + o]``.

    Parameters
    ----------
    id, source, target : str
        Projection id and population ids; both populations have the same shape.
    axes : tuple of str
        The map axes the kernel spans (kernel dimension ``i`` along ``axes[i]``).
    kernel : ndarray
        Weights with odd size along every axis, centred (offset 0 in the middle).
        Zero entries are not synapses.
    edge : tuple of {"wrap", "clip"}
        Per axis: ``wrap`` is circular, ``clip`` drops taps beyond the map.
    delays : ndarray of int, optional
        Per-tap delays, shaped like ``kernel``.
    origin : dict
        Provenance (``node``, ``motif``).
    """

    id: str
    source: str
    target: str
    axes: tuple[str, ...]
    kernel: np.ndarray
    edge: tuple[EdgeMode, ...]
    delays: np.ndarray | None = None
    origin: dict[str, str] = field(default_factory=dict)
    kind: Literal["stencil"] = "stencil"

    def __post_init__(self) -> None:
        pid = self.id
        set_ = object.__setattr__
        set_(self, "axes", tuple(self.axes))
        set_(self, "edge", tuple(self.edge))
        k = _finite_weights(self.kernel, pid)
        if k.ndim != len(self.axes) or any(n % 2 == 0 for n in k.shape):
            raise NetworkError(
                f"projection {pid!r}: kernel shape {k.shape} must have one odd size per axis "
                f"of {self.axes}",
                node=pid,
            )
        if len(self.edge) != len(self.axes) or not set(self.edge) <= {"wrap", "clip"}:
            raise NetworkError(
                f"projection {pid!r}: edge {self.edge} must give 'wrap' or 'clip' for each axis "
                f"of {self.axes}",
                node=pid,
            )
        set_(self, "kernel", k)
        set_(self, "delays", _int_delays(self.delays, k.shape, pid))

    @property
    def radius(self) -> tuple[int, ...]:
        """Kernel half-widths per axis."""
        return tuple(n // 2 for n in self.kernel.shape)

    @property
    def n_taps(self) -> int:
        """Non-zero kernel entries: the synapses of one target neuron (away from clipped edges)."""
        return int(np.count_nonzero(self.kernel))

    @property
    def n_synapses(self) -> int:
        """Stored synapses: the kernel is stored once (``n_taps``)."""
        return self.n_taps

    @property
    def max_delay(self) -> int:
        """The largest tap delay in steps (0 without delays)."""
        return 0 if self.delays is None else int(self.delays.max())

    def by_delay(self) -> dict[int, np.ndarray]:
        """The kernel split by delay: ``{d: K_d}`` with ``K = Σ_d K_d``.

        Examples
        --------
        >>> import numpy as np
        >>> p = StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                       kernel=np.array([1.0, 2.0, 3.0]), edge=("clip",),
        ...                       delays=np.array([0, 1, 0]))
        >>> {d: k.tolist() for d, k in p.by_delay().items()}
        {0: [1.0, 0.0, 3.0], 1: [0.0, 2.0, 0.0]}
        """
        if self.delays is None:
            return {0: self.kernel}
        out = {
            int(d): np.where(self.delays == d, self.kernel, 0.0)
            for d in np.unique(self.delays[self.kernel != 0])
        }
        return out or {0: np.zeros_like(self.kernel)}


Projection = MatrixProjection | StencilProjection


def weights_of(p: Projection) -> np.ndarray:
    """The stored weight array of a projection: a stencil's kernel, a matrix's dense
    weights or its sparse values.

    Examples
    --------
    >>> weights_of(StencilProjection(id="s", source="a", target="b", axes=("i",),
    ...                              kernel=np.array([1.0, -1.0, 0.5]), edge=("clip",))).tolist()
    [1.0, -1.0, 0.5]
    """
    if isinstance(p, StencilProjection):
        return p.kernel
    return p.weights if p.weights is not None else p.values


def with_weights(p: Projection, w: np.ndarray) -> Projection:
    """``p`` with its stored weight array (as :func:`weights_of` returns it) replaced."""
    if isinstance(p, StencilProjection):
        return replace(p, kernel=w)
    return replace(p, weights=w) if p.weights is not None else replace(p, values=w)
