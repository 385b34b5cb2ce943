r"""Synapse counts of projections: non-zero patterns, stencil degrees, instances, stored entries.

A matrix projection's synapses are the non-zero weights ``W[c, p]``, repeated over
the pass-through (repetition) axes; a stencil's are its non-zero taps at every
target position, minus the taps that fall off a ``clip`` edge.  The helpers here
also convert flat (row-major) neuron indices to coordinates along named axes.

The counts themselves are the projection kinds' own (``wired_synapses``,
``nonzero_pattern``, ``degree_map``: see :mod:`compiler.snn.projections`); the
functions here keep their names for the hardware modules.

Examples
--------
>>> from compiler.snn import Population
>>> p = Population(id="y", shape={"a": 2, "b": 3})
>>> strides(p), [c.tolist() for c in coords(p, np.array([0, 4, 5]), ("b", "a"))]
({'a': 3, 'b': 1}, [[0, 1, 2], [0, 1, 1]])
"""

from __future__ import annotations

from math import prod

import numpy as np
import scipy.sparse as sp

from compiler.snn import MatrixProjection, Population, Projection, SpikingNetwork, StencilProjection

__all__ = ["coords", "nonzero_pattern", "ravel", "stencil_degree_map", "stored_synapses",
           "strides", "synapse_instances"]

def strides(pop: Population) -> dict[str, int]:
    """Row-major stride of every axis of ``pop``."""
    dims = pop.dims
    return {a: prod(dims[i + 1:]) for i, a in enumerate(pop.axes)}


def coords(pop: Population, flat: np.ndarray, axes: tuple[str, ...]) -> list[np.ndarray]:
    """Coordinates of flat neuron indices along ``axes``."""
    st = strides(pop)
    return [(flat // st[a]) % pop.shape[a] for a in axes]


def ravel(pop: Population, flat: np.ndarray, axes: tuple[str, ...]) -> np.ndarray:
    """Row-major flat index of neurons ``flat`` of ``pop`` on the grid of ``axes``.

    With no ``axes`` (a matrix that contracts or produces no axis) every index is 0.

    Examples
    --------
    >>> from compiler.snn import Population
    >>> p = Population(id="y", shape={"a": 2, "b": 3})
    >>> ravel(p, np.array([0, 4, 5]), ("b", "a")).tolist(), ravel(p, np.array([0, 4]), ()).tolist()
    ([0, 3, 5], [0, 0])
    """
    out = np.zeros(flat.shape, np.int64)
    for c, a in zip(coords(pop, flat, axes), axes, strict=True):
        out = out * pop.shape[a] + c
    return out


def nonzero_pattern(proj: MatrixProjection) -> sp.csr_matrix:
    """Boolean ``(n_in, n_out)`` pattern of the non-zero weights (``proj.nonzero_pattern``).

    Examples
    --------
    >>> w = MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
    ...                      weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
    >>> nonzero_pattern(w).toarray().tolist()
    [[True, False], [True, True]]
    """
    return proj.nonzero_pattern


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
    return proj.degree_map(pop, incoming=incoming)


def synapse_instances(proj: Projection, pops: dict[str, Population]) -> int:
    """Synapses of ``proj`` counting every repetition; stencil taps off a ``clip`` edge excluded.

    Examples
    --------
    >>> pops = {"b": Population(id="b", shape={"r": 4})}
    >>> synapse_instances(StencilProjection(id="k", source="b", target="b", axes=("r",),
    ...                                     kernel=np.ones(3), edge=("clip",)), pops)
    10
    """
    return proj.wired_synapses(pops[proj.source], pops[proj.target])


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
