r"""Synapse counts of projections: non-zero patterns, stencil degrees, instances, stored entries.

A matrix projection's synapses are the non-zero weights ``W[c, p]``, repeated over
the pass-through (repetition) axes; a stencil's are its non-zero taps at every
target position, minus the taps that fall off a ``clip`` edge.  The helpers here
also convert flat (row-major) neuron indices to coordinates along named axes.

Projections are treated as immutable: a matrix's non-zero pattern is computed once
per projection object and remembered while the object lives.

Examples
--------
>>> from compiler.snn import Population
>>> p = Population(id="y", shape={"a": 2, "b": 3})
>>> strides(p), [c.tolist() for c in coords(p, np.array([0, 4, 5]), ("b", "a"))]
({'a': 3, 'b': 1}, [[0, 1, 2], [0, 1, 1]])
"""

from __future__ import annotations

from math import prod
from weakref import WeakKeyDictionary

import numpy as np
import scipy.sparse as sp

from compiler.snn import MatrixProjection, Population, SpikingNetwork, StencilProjection

__all__ = ["coords", "nonzero_pattern", "ravel", "stencil_degree_map", "stored_synapses",
           "strides", "synapse_instances"]

_PATTERNS: WeakKeyDictionary[MatrixProjection, sp.csr_matrix] = WeakKeyDictionary()


def strides(pop: Population) -> dict[str, int]:
    """Row-major stride of every axis of ``pop``."""
    dims = pop.dims
    return {a: prod(dims[i + 1:]) for i, a in enumerate(pop.axes)}


def coords(pop: Population, flat: np.ndarray, axes: tuple[str, ...]) -> list[np.ndarray]:
    """Coordinates of flat neuron indices along ``axes``."""
    st = strides(pop)
    return [(flat // st[a]) % pop.shape[a] for a in axes]


def ravel(cs: list[np.ndarray], sizes: list[int]) -> np.ndarray:
    """Row-major flat index of coordinates ``cs`` in a grid of ``sizes``."""
    out = np.zeros_like(cs[0]) if cs else np.zeros(0, np.int64)
    for c, n in zip(cs, sizes, strict=True):
        out = out * n + c
    return out


def nonzero_pattern(proj: MatrixProjection) -> sp.csr_matrix:
    """Boolean ``(n_in, n_out)`` pattern of the non-zero weights (computed once per projection).

    Examples
    --------
    >>> w = MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
    ...                      weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
    >>> nonzero_pattern(w).toarray().tolist()
    [[True, False], [True, True]]
    """
    found = _PATTERNS.get(proj)
    if found is not None:
        return found
    if proj.weights is not None:
        m = sp.csr_matrix(proj.weights != 0)
    else:
        keep = proj.values != 0
        m = sp.csr_matrix((np.ones(int(keep.sum()), bool), (proj.rows[keep], proj.cols[keep])),
                          shape=proj.n_in_out)
        m.sum_duplicates()
        m = m.astype(bool)
    _PATTERNS[proj] = m
    return m


def stencil_degree_map(proj: StencilProjection, pop: Population, *, incoming: bool) -> np.ndarray:
    r"""Synapses per neuron over the stencil's map axes (in ``proj.axes`` order).

    ``incoming``: :math:`\sum_o [K_o \ne 0]\,[x + o \in \text{map}]` (taps a target
    neuron receives); otherwise :math:`\sum_o [K_o \ne 0]\,[x - o \in \text{map}]`
    (targets a source neuron reaches).  ``wrap`` axes never lose a tap.

    Examples
    --------
    >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
    ...                       kernel=np.array([1.0, 1.0, 1.0]), edge=("clip",))
    >>> stencil_degree_map(k, Population(id="b", shape={"r": 4}), incoming=True).tolist()
    [2, 3, 3, 2]
    """
    mask = (proj.kernel != 0).astype(np.float64)
    inside = np.ones([pop.shape[a] for a in proj.axes])
    pad = [(r, r) for r in proj.radius]
    for ax, (edge, width) in enumerate(zip(proj.edge, pad, strict=True)):
        widths = [(0, 0)] * inside.ndim
        widths[ax] = width
        inside = np.pad(inside, widths, mode="wrap" if edge == "wrap" else "constant")
    from scipy import signal  # imported here: scipy.signal takes ~1 s to import

    op = signal.correlate if incoming else signal.convolve
    return np.rint(op(inside, mask, mode="valid")).astype(np.int64)


def synapse_instances(proj: MatrixProjection | StencilProjection,
                      pops: dict[str, Population]) -> int:
    """Synapses of ``proj`` counting every repetition; stencil taps off a ``clip`` edge excluded.

    Examples
    --------
    >>> pops = {"b": Population(id="b", shape={"r": 4})}
    >>> synapse_instances(StencilProjection(id="k", source="b", target="b", axes=("r",),
    ...                                     kernel=np.ones(3), edge=("clip",)), pops)
    10
    """
    if isinstance(proj, StencilProjection):
        tgt = pops[proj.target]
        deg = stencil_degree_map(proj, tgt, incoming=True)
        return int(deg.sum()) * (tgt.size // deg.size)
    src = pops[proj.source]
    reps = src.size // prod(src.shape[a] for a in proj.contract)
    return reps * int(nonzero_pattern(proj).nnz)


def stored_synapses(network: SpikingNetwork, shared_weights: bool) -> int:
    """A lower bound on the entries a network stores: shared weights once, else every instance.

    Examples
    --------
    >>> net = SpikingNetwork(name="s", n_steps=2, populations=[
    ...     Population(id="a", shape={"r": 4}, source=True), Population(id="b", shape={"r": 4})],
    ...     projections=[StencilProjection(id="k", source="a", target="b", axes=("r",),
    ...                                    kernel=np.ones(3), edge=("clip",))])
    >>> stored_synapses(net, True), stored_synapses(net, False)
    (3, 10)
    """
    pops = network.population
    if shared_weights:
        return sum(p.n_synapses for p in network.projections)
    return sum(synapse_instances(p, pops) for p in network.projections)
