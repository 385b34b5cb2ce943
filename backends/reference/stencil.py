r"""Delivery of a :class:`~compiler.snn.StencilProjection`: one kernel correlated over map axes.

.. math:: I[y] = \sum_o K[o]\, s[y + o]

is delivered event by event: a spike at ``x`` adds ``K[o]`` to ``y = x - o``
for every non-zero tap, wrapping (``wrap``) or dropped beyond the map
(``clip``) per axis, and the contributions are summed with ``np.add.at`` in
(event, tap) order (exact in int64).  Axes are matched by name, so source and target may store
them in different orders.  Events far enough from every edge (*interior*: no
tap wraps or leaves the map) take a fast path ``flat(y) = base(x) - Δ(o)`` with
precomputed flat offsets ``Δ``; the others go through the per-axis rule.  The
work is ``spikes × taps``, independent of the map size.

When most neurons carry a weighted event (the closed form's arrival features)
the map is delivered *densely*: the values are scattered onto the source map,
padded per axis (wrapped, or with the fill value), and every distinct weight
adds its taps' shifted views, ``I = Σ_w w Σ_{o: K[o] = w} s[· + o]`` — the work
is ``taps × map`` in a few large array operations.  The same views give
:meth:`StencilDelivery.weight_not_after`, the weight of the taps whose arrival
is no later than a per-target step (the closed form's gated neurons).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from math import prod

import numpy as np

from backends.reference.stencil_synapses import inside_counts
from compiler.snn.network import Population
from compiler.snn.projections import StencilProjection

__all__ = ["StencilDelivery"]

_CHUNK_PAIRS = 1 << 22

#: Weighted events above ``1 / _DENSE_FRACTION`` of the batch's neurons go the dense way.
_DENSE_FRACTION = 4


@dataclass(frozen=True, eq=False)
class StencilDelivery:
    """The delivery plan of one :class:`~compiler.snn.StencilProjection`.

    Attributes
    ----------
    delays : tuple of int
        The delay classes, ascending.
    offsets : tuple of ndarray
        Per delay class, the ``(n_taps, n_map)`` tap offsets ``o`` (kernel index − radius).
    tap_weights : tuple of ndarray
        Per delay class, the ``(n_taps,)`` weights ``K[o]``.
    map_axes : tuple of int
        Positions of the kernel axes in the target's axis order.
    wrap : tuple of bool
        Per kernel axis, wrap (True) or clip.
    src_axis_of : tuple of int
        For each target axis, the position of the same-named source axis.
    base_of : ndarray
        Per source neuron, the flat target index of the same position.
    deltas : tuple of ndarray
        Per delay class, the flat target offset of each tap.
    interior : tuple of ndarray
        Per delay class, per source neuron: no tap wraps or leaves the map.
    synapses : tuple of ndarray
        Per delay class, per source neuron: taps landing inside the map.
    """

    id: str
    source: str
    target: str
    delays: tuple[int, ...]
    offsets: tuple[np.ndarray, ...]
    tap_weights: tuple[np.ndarray, ...]
    map_axes: tuple[int, ...]
    wrap: tuple[bool, ...]
    src_axis_of: tuple[int, ...]
    src_dims: tuple[int, ...]
    tgt_dims: tuple[int, ...]
    base_of: np.ndarray
    deltas: tuple[np.ndarray, ...]
    interior: tuple[np.ndarray, ...]
    synapses: tuple[np.ndarray, ...]
    integer: bool

    @classmethod
    def build(
        cls, proj: StencilProjection, src: Population, tgt: Population, integer: bool = False
    ) -> StencilDelivery:
        """Precompute the taps of ``proj`` per delay class and the per-neuron edge facts.

        Parameters
        ----------
        proj : StencilProjection
        src, tgt : Population
            Its source and target (same axes, any order).
        integer : bool
            Return int64 currents.

        Returns
        -------
        StencilDelivery

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import Population, StencilProjection
        >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                       kernel=np.array([1.0, 0.0, 2.0]), edge=("clip",))
        >>> a = Population(id="a", shape={"r": 4}, source=True)
        >>> d = StencilDelivery.build(k, a, Population(id="b", shape={"r": 4}))
        >>> d.offsets[0].ravel().tolist(), d.current(0, np.array([2]), 1).tolist()
        ([-1, 1], [[0.0, 2.0, 0.0, 1.0]])
        >>> d.synapses[0].tolist(), d.interior[0].tolist()
        ([1, 2, 2, 1], [False, True, True, False])
        """
        classes = proj.by_delay() or {0: np.zeros_like(proj.kernel)}  # all-zero kernel
        delays = tuple(sorted(classes))
        taps = [np.argwhere(classes[d] != 0) for d in delays]
        offsets = tuple(t - np.array(proj.radius) for t in taps)
        map_axes = tuple(tgt.axes.index(a) for a in proj.axes)
        src_axis_of = tuple(src.axes.index(a) for a in tgt.axes)
        coords = np.unravel_index(np.arange(src.size), src.dims)
        strides = np.array([prod(tgt.dims[i + 1:]) for i in range(len(tgt.dims))])
        base_of = sum(coords[src_axis_of[i]] * strides[i] for i in range(len(tgt.dims)))
        interior = []
        for off in offsets:
            inside = np.ones(src.size, bool)
            for j, axis in enumerate(map_axes):
                if off.size:
                    c = coords[src_axis_of[axis]]
                    inside &= (c - off[:, j].max() >= 0) & (c - off[:, j].min() < tgt.dims[axis])
            interior.append(inside)
        plan = cls(
            id=proj.id, source=proj.source, target=proj.target, delays=delays, offsets=offsets,
            tap_weights=tuple(classes[d][tuple(t.T)].astype(np.int64 if integer else np.float64)
                              for d, t in zip(delays, taps, strict=True)),
            map_axes=map_axes, wrap=tuple(e == "wrap" for e in proj.edge),
            src_axis_of=src_axis_of, src_dims=src.dims, tgt_dims=tgt.dims,
            base_of=np.asarray(base_of, np.int64),
            deltas=tuple(off @ strides[list(map_axes)] for off in offsets),
            interior=tuple(interior), synapses=(), integer=integer,
        )
        object.__setattr__(plan, "synapses", tuple(plan._count_synapses(k)
                                                   for k in range(len(delays))))
        return plan

    @property
    def src_size(self) -> int:
        """Neurons in the source population."""
        return prod(self.src_dims)

    @property
    def weight_nbytes(self) -> int:
        """Bytes held by the taps (independent of the map size)."""
        return sum(w.nbytes + o.nbytes for w, o in zip(self.tap_weights, self.offsets,
                                                         strict=True))

    def _count_synapses(self, k: int) -> np.ndarray:
        """Per source neuron, the taps of delay class ``k`` landing inside the map
        (:func:`~backends.reference.stencil_synapses.inside_counts`; over more than two
        clipped axes, :meth:`_count_synapses_by_events`)."""
        counts = inside_counts(self.offsets[k], self.map_axes, self.wrap, self.src_axis_of,
                               self.src_dims, self.tgt_dims)
        return self._count_synapses_by_events(k) if counts is None else counts

    def _count_synapses_by_events(self, k: int) -> np.ndarray:
        """:meth:`_count_synapses` by enumerating every source neuron's taps (any axes)."""
        n_taps = self.offsets[k].shape[0]
        step = max(1, _CHUNK_PAIRS // max(1, n_taps))
        neurons = np.arange(self.src_size)
        return np.concatenate([self._edge_targets(k, neurons[i:i + step], 1)[1].sum(axis=1)
                               for i in range(0, self.src_size, step)] or [np.zeros(0, int)])

    def _edge_targets(
        self, k: int, events: np.ndarray, n_batch: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Flat targets ``(events, taps)`` and their validity, axis by axis (any event)."""
        coords = np.unravel_index(events, (n_batch, *self.src_dims))
        offsets = self.offsets[k]
        flat = coords[0][:, None]
        valid = np.ones((events.size, offsets.shape[0]), bool)
        for axis, size in enumerate(self.tgt_dims):
            c = coords[1 + self.src_axis_of[axis]][:, None]
            if axis in self.map_axes:
                j = self.map_axes.index(axis)
                c = c - offsets[None, :, j]
                if self.wrap[j]:
                    c = c % size
                else:
                    valid &= (c >= 0) & (c < size)
            flat = flat * size + c
        return np.broadcast_to(flat, valid.shape), valid

    def current(
        self, k: int, events: np.ndarray, n_batch: int, values: np.ndarray | None = None
    ) -> np.ndarray:
        """The current of the events of delay class ``k``: ``(n_batch, *target_shape)``.

        ``values`` (default 1 per event) scales each event's contribution.
        """
        n_src, n_tgt = self.src_size, prod(self.tgt_dims)
        if values is not None and events.size * _DENSE_FRACTION >= n_batch * n_src:
            dtype = np.int64 if self.integer else np.float64
            dense = np.bincount(events, weights=values, minlength=n_batch * n_src)
            return self.correlate(k, dense.astype(dtype, copy=False).reshape(
                n_batch, *self.src_dims))
        b, n = np.divmod(events, n_src)
        inner = self.interior[k][n]
        w = self.tap_weights[k][None, :]
        w_ev = np.broadcast_to(w if values is None else values[:, None] * w,
                               (events.size, w.shape[1]))
        flat_in = (b[inner] * n_tgt + self.base_of[n[inner]])[:, None] - self.deltas[k][None, :]
        flat_edge, valid = self._edge_targets(k, events[~inner], n_batch)
        flat = np.concatenate([flat_in.ravel(), flat_edge[valid]])
        weights = np.concatenate([w_ev[inner].ravel(), w_ev[~inner][valid]])
        if self.integer:
            out = np.zeros(n_batch * n_tgt, np.int64)
            np.add.at(out, flat, weights)
        else:  # bincount adds in array order, like add.at, and is several times faster
            out = np.bincount(flat, weights=weights, minlength=n_batch * n_tgt)
        return out.reshape(n_batch, *self.tgt_dims)

    def _shifted(self, k: int, source_map: np.ndarray, fill) -> list[tuple[object, list]]:
        """Per distinct tap weight, the views ``s[· + o]`` of its taps in the target's layout.

        ``source_map`` is ``(n_batch, *source_shape)``; positions beyond a
        clipped edge read ``fill``.
        """
        tmap = source_map.transpose(0, *(1 + a for a in self.src_axis_of))
        before, after, groups = self._tap_slices[k]
        padded = _pad(tmap, self.map_axes, before, after, self.wrap, fill)
        return [(w, [padded[index] for index in slices]) for w, slices in groups]

    @cached_property
    def _tap_slices(self) -> tuple:
        """Per class: the margins before/after each map axis and, per distinct weight, the
        index of every tap's view into the padded map (built once)."""
        out = []
        for k, offsets in enumerate(self.offsets):
            before = np.maximum(0, -offsets.min(axis=0, initial=0))
            after = np.maximum(0, offsets.max(axis=0, initial=0))
            groups: dict[object, list] = {}
            for w, off in zip(self.tap_weights[k].tolist(), offsets, strict=True):
                index = [slice(None)] * (1 + len(self.tgt_dims))
                for j, axis in enumerate(self.map_axes):
                    start = int(before[j] + off[j])
                    index[1 + axis] = slice(start, start + self.tgt_dims[axis])
                groups.setdefault(w, []).append(tuple(index))
            out.append((before, after, list(groups.items())))
        return tuple(out)

    def correlate(self, k: int, source_map: np.ndarray) -> np.ndarray:
        r"""Dense delivery of a whole value map: ``I[y] = Σ_o K[o] s[y + o]``.

        Parameters
        ----------
        k : int
            Delay class.
        source_map : ndarray
            ``(n_batch, *source_shape)`` values (one per source neuron).

        Returns
        -------
        ndarray
            ``(n_batch, *target_shape)``; taps of equal weight are summed first,
            so float sums may be ordered differently from :meth:`current`'s
            event-by-event path (equal whenever the sums are exact).

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import Population, StencilProjection
        >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                       kernel=np.array([1.0, 0.0, 2.0]), edge=("wrap",))
        >>> a = Population(id="a", shape={"r": 4}, source=True)
        >>> d = StencilDelivery.build(k, a, Population(id="b", shape={"r": 4}))
        >>> d.correlate(0, np.array([[1.0, 2.0, 3.0, 4.0]])).tolist()
        [[8.0, 7.0, 10.0, 5.0]]
        """
        if source_map.dtype == bool:  # a spike mask: count in 16 bits (exact), then weigh
            out = np.zeros((source_map.shape[0], *self.tgt_dims),
                           np.int64 if self.integer else np.float64)
            source_map = source_map.astype(self._count_dtype(k))
        else:
            out = np.zeros((source_map.shape[0], *self.tgt_dims), source_map.dtype)
        for w, views in self._shifted(k, source_map, 0):
            part = views[0].copy()
            for view in views[1:]:
                part += view
            out += np.multiply(part, w, dtype=out.dtype)
        return out

    def _count_dtype(self, k: int):
        """The narrowest integer that holds a count of class ``k``'s taps."""
        return np.uint16 if self.offsets[k].shape[0] < np.iinfo(np.uint16).max else np.int64

    def weight_not_after(self, k: int, arrive_map: np.ndarray, when: np.ndarray) -> np.ndarray:
        r"""Per target ``y``: ``Σ_o K[o] [a(y + o) <= t_y]`` — the weight arrived by ``t_y``.

        Parameters
        ----------
        k : int
            Delay class.
        arrive_map : ndarray of int64
            ``(n_batch, *source_shape)`` arrival step of each source neuron's
            single spike through this class; a step larger than every ``when``
            (e.g. ``np.iinfo(np.int64).max``) for none.
        when : ndarray of int64
            ``(n_batch, *target_shape)`` the step ``t_y`` per target.

        Returns
        -------
        ndarray
            ``(n_batch, *target_shape)`` in the plan's arithmetic: distinct weights
            times the counts of their taps (exact in int64, and in float64 when the
            weights are dyadic).

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn import Population, StencilProjection
        >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                       kernel=np.array([-1.0, 0.0, -1.0]), edge=("clip",))
        >>> a = Population(id="a", shape={"r": 4}, source=True)
        >>> d = StencilDelivery.build(k, a, Population(id="b", shape={"r": 4}))
        >>> d.weight_not_after(0, np.array([[0, 5, 2, 9]]), np.array([[3, 3, 3, 3]])).tolist()
        [[0.0, -2.0, 0.0, -1.0]]
        """
        out = np.zeros(when.shape, np.int64 if self.integer else np.float64)
        # arrivals after the last t_y never count, so clip them there and compare in 16 bits
        late = int(when.max()) + 1 if when.size else 0
        narrow = np.int16 if late < np.iinfo(np.int16).max else np.int64
        arrive_map = np.minimum(arrive_map, late).astype(narrow, copy=False)
        when = when.astype(narrow, copy=False)
        count = np.zeros(when.shape, self._count_dtype(k))
        hit = np.empty(when.shape, bool)
        for w, views in self._shifted(k, arrive_map, late):
            count[...] = 0
            for view in views:
                np.less_equal(view, when, out=hit)
                count += hit
            out += np.multiply(count, w, dtype=out.dtype)
        return out

    def n_events(self, k: int, events: np.ndarray) -> int:
        """Synaptic events of the events of delay class ``k`` (taps landing inside the map)."""
        # one vectorised remainder, not np.take(mode="wrap") (a loop per index, see matrix.py)
        return int(self.synapses[k][events % self.src_size].sum())


def _pad(tmap: np.ndarray, map_axes: tuple[int, ...], before: np.ndarray, after: np.ndarray,
         wrap: tuple[bool, ...], fill) -> np.ndarray:
    """``tmap`` padded along each map axis as ``np.pad`` does axis after axis: ``wrap``
    copies the far side, else ``fill`` (without np.pad's per-call overhead)."""
    if any(w and max(before[j], after[j]) > tmap.shape[1 + a]
           for j, (a, w) in enumerate(zip(map_axes, wrap, strict=True))):
        for j, a in enumerate(map_axes):  # margins wider than the map: np.pad repeats it
            pad = [(0, 0)] * tmap.ndim
            pad[1 + a] = (int(before[j]), int(after[j]))
            tmap = (np.pad(tmap, pad, mode="wrap") if wrap[j]
                    else np.pad(tmap, pad, constant_values=fill))
        return tmap
    shape = list(tmap.shape)
    inner = [slice(None)] * tmap.ndim
    for j, a in enumerate(map_axes):
        shape[1 + a] += int(before[j] + after[j])
        inner[1 + a] = slice(int(before[j]), int(before[j]) + tmap.shape[1 + a])
    padded = np.empty(shape, tmap.dtype)
    padded[tuple(inner)] = tmap
    # each axis's margins over the whole extent of the others: a later axis overwrites its
    # own margins, so the result is np.pad's (axis 0 padded first, then axis 1 over it)
    for j, a in enumerate(map_axes):
        b, e, n = int(before[j]), int(after[j]), tmap.shape[1 + a]
        for part, src in ((slice(0, b), slice(n, n + b)), (slice(b + n, b + n + e),
                                                            slice(b, b + e))):
            if part.stop > part.start:
                lead = [slice(None)] * tmap.ndim
                lead[1 + a] = part
                if wrap[j]:
                    take = list(lead)
                    take[1 + a] = src
                    padded[tuple(lead)] = padded[tuple(take)]
                else:
                    padded[tuple(lead)] = fill
    return padded
