r"""Projections expanded into explicit synapse lists (one row per synapse instance).

A chip, Brian2 and NIR have no notion of weights *shared* over repetition axes
or of a kernel *correlated* over a map: they want every synapse spelled out.
:func:`expand_projection` turns one projection into a :class:`SynapseList`
``(pre, post, weight, delay)`` of flat neuron indices (row-major over each
population's own axis order), by the projection's *type* through the explicit
registry :data:`EXPANDERS` (the backend's own table: the compile path does not know it):

``matrix``
    ``W`` of shape ``(n_in, n_out)`` instantiated for every repetition ``r``:
    ``pre = S[r, i]``, ``post = T[r, j]`` for each non-zero ``W[i, j]``, where
    ``S`` (``T``) lists the source (target) neurons with the repetition axes
    first, in the source's order, and the ``contract`` (``produce``) axes last.
``stencil``
    ``I[y] = Σ_o K[o] s[y + o]``: for every target ``y`` and non-zero tap ``o``
    a synapse from ``x = y + o`` (wrapped, or dropped beyond a ``clip`` edge).

Zero weights are not synapses.  The expansion is the reference simulator's
arithmetic written out: :func:`dense_weights` of a list equals the current the
reference delivery computes for one spike of each source neuron.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import MatrixProjection, Population
>>> a = Population(id="a", shape={"rep": 2, "i": 2}, source=True)
>>> b = Population(id="b", shape={"o": 1, "rep": 2})
>>> p = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
...                      weights=np.array([[1.0], [3.0]]), delays=np.array([[0], [2]]))
>>> s = expand_projection(p, a, b)
>>> s.pre.tolist(), s.post.tolist(), s.weight.tolist(), s.delay.tolist()
([0, 1, 2, 3], [0, 0, 1, 1], [1.0, 3.0, 1.0, 3.0], [0, 2, 0, 2])
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from compiler.snn.network import Population
from compiler.snn.projections import MatrixProjection, Projection, StencilProjection

__all__ = ["SynapseList", "EXPANDERS", "expand_projection", "dense_weights"]


@dataclass(frozen=True, eq=False)
class SynapseList:
    """Every synapse of one projection instance-by-instance.

    Attributes
    ----------
    pre, post : ndarray of int64
        Flat source and target neuron indices.
    weight : ndarray of float64
        Synaptic weights (non-zero).
    delay : ndarray of int64
        Delays in steps.
    """

    pre: np.ndarray
    post: np.ndarray
    weight: np.ndarray
    delay: np.ndarray

    def __len__(self) -> int:
        return int(self.pre.size)

    def replicate(self, n_frames: int, n_pre: int, n_post: int) -> SynapseList:
        """The list repeated for ``n_frames`` independent copies of both populations.

        Examples
        --------
        >>> s = SynapseList(np.array([0]), np.array([1]), np.array([2.0]), np.array([0]))
        >>> r = s.replicate(2, n_pre=3, n_post=4)
        >>> r.pre.tolist(), r.post.tolist()
        ([0, 3], [1, 5])
        """
        f = np.arange(n_frames)[:, None]
        return SynapseList((f * n_pre + self.pre[None, :]).ravel(),
                           (f * n_post + self.post[None, :]).ravel(),
                           np.tile(self.weight, n_frames), np.tile(self.delay, n_frames))


def _grouped(pop: Population, first: list[str], last: tuple[str, ...]) -> np.ndarray:
    """Flat indices of ``pop`` arranged ``(prod(first axes), prod(last axes))``."""
    idx = np.arange(pop.size).reshape(pop.dims)
    perm = [pop.axes.index(a) for a in (*first, *last)]
    n_last = int(np.prod([pop.shape[a] for a in last], dtype=np.int64))
    return idx.transpose(perm).reshape(-1, n_last)


def expand_matrix(proj: MatrixProjection, src: Population, tgt: Population) -> SynapseList:
    """Synapses of a :class:`MatrixProjection` for every repetition (see the module doc)."""
    reps = [a for a in src.axes if a not in proj.contract]
    pre_of, post_of = _grouped(src, reps, proj.contract), _grouped(tgt, reps, proj.produce)
    if proj.weights is not None:
        rows, cols = np.nonzero(proj.weights)
        w = proj.weights[rows, cols]
        d = proj.delays[rows, cols] if proj.delays is not None else np.zeros(rows.size, np.int64)
    else:
        live = proj.values != 0
        rows, cols, w = proj.rows[live], proj.cols[live], proj.values[live]
        d = proj.delays[live] if proj.delays is not None else np.zeros(rows.size, np.int64)
    n_rep = pre_of.shape[0]
    return SynapseList(pre_of[:, rows].ravel(), post_of[:, cols].ravel(),
                       np.tile(w, n_rep), np.tile(d.astype(np.int64), n_rep))


def expand_stencil(proj: StencilProjection, src: Population, tgt: Population) -> SynapseList:
    """Synapses of a :class:`StencilProjection`: ``x = y + o`` for every target and tap."""
    taps = np.argwhere(proj.kernel != 0)
    offsets = taps - np.array(proj.radius)
    w = proj.kernel[tuple(taps.T)]
    d = (proj.delays[tuple(taps.T)] if proj.delays is not None
         else np.zeros(len(taps), np.int64))
    coords = np.unravel_index(np.arange(tgt.size), tgt.dims)
    valid = np.ones((tgt.size, len(taps)), bool)
    src_coord = {}
    for axis, name in enumerate(tgt.axes):
        c = np.broadcast_to(coords[axis][:, None], valid.shape)
        if name in proj.axes:
            j = proj.axes.index(name)
            c = c + offsets[None, :, j]
            size = tgt.dims[axis]
            if proj.edge[j] == "wrap":
                c = c % size
            else:
                valid &= (c >= 0) & (c < size)
                c = np.clip(c, 0, size - 1)
        src_coord[name] = c
    pre = np.ravel_multi_index(tuple(src_coord[a] for a in src.axes), src.dims)
    post = np.broadcast_to(np.arange(tgt.size)[:, None], valid.shape)
    return SynapseList(pre[valid].astype(np.int64), post[valid].astype(np.int64),
                       np.broadcast_to(w, valid.shape)[valid].astype(np.float64),
                       np.broadcast_to(d, valid.shape)[valid].astype(np.int64))


#: Synapse expanders by projection type: ``(projection, source, target) -> SynapseList``.
EXPANDERS: Mapping[type, Callable[..., SynapseList]] = {
    MatrixProjection: expand_matrix,
    StencilProjection: expand_stencil,
}


def expand_projection(
    proj: Projection, src: Population, tgt: Population,
    expanders: Mapping[type, Callable[..., SynapseList]] = EXPANDERS,
) -> SynapseList:
    """Every synapse instance of ``proj`` between ``src`` and ``tgt``.

    Parameters
    ----------
    proj : MatrixProjection or StencilProjection
        The projection (from a validated network).
    src, tgt : Population
        Its source and target populations.
    expanders : mapping
        Expander per projection type (default :data:`EXPANDERS`).

    Returns
    -------
    SynapseList

    Raises
    ------
    KeyError
        Never for the built-in kinds; an unknown type is the caller's to report.

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import Population, StencilProjection
    >>> a = Population(id="a", shape={"r": 3}, source=True)
    >>> k = StencilProjection(id="k", source="a", target="b", axes=("r",),
    ...                       kernel=np.array([1.0, 0.0, 2.0]), edge=("clip",))
    >>> s = expand_projection(k, a, Population(id="b", shape={"r": 3}))
    >>> sorted(zip(s.post.tolist(), s.pre.tolist(), s.weight.tolist()))
    [(0, 1, 2.0), (1, 0, 1.0), (1, 2, 2.0), (2, 1, 1.0)]
    """
    return expanders[type(proj)](proj, src, tgt)


def dense_weights(syn: SynapseList, n_pre: int, n_post: int, delay: int | None = None
                  ) -> np.ndarray:
    """The ``(n_post, n_pre)`` weight matrix of the synapses (of one ``delay`` if given).

    Duplicate ``(pre, post)`` pairs add up, as their currents do.

    Examples
    --------
    >>> s = SynapseList(np.array([0, 0]), np.array([1, 1]), np.array([2.0, 0.5]),
    ...                 np.array([0, 1]))
    >>> dense_weights(s, 1, 2).tolist(), dense_weights(s, 1, 2, delay=1).tolist()
    ([[0.0], [2.5]], [[0.0], [0.5]])
    """
    keep = slice(None) if delay is None else syn.delay == delay
    out = np.zeros((n_post, n_pre))
    np.add.at(out, (syn.post[keep], syn.pre[keep]), syn.weight[keep])
    return out
