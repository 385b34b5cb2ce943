r"""The stencil projection kind: one kernel correlated over map axes.

``I[x] = Σ_o K[o] s[x + o]`` over the map axes ``axes`` of a source and a
target of the same shape, offsets ``o`` centred on the kernel middle, ``wrap``
or ``clip`` (no synapse) beyond the map per axis.  The kind answers the
projection protocol (:class:`compiler.snn.projections.ProjectionKind`) for itself:

* stored weights: the kernel ``K`` (stored once);
* nominal synapse instances :math:`|T| \cdot \mathrm{nnz}(K)` (edges ignored);
* wired synapses :math:`\sum_x \sum_o [K_o \ne 0]\,[x + o \in \text{map}]` (clipped taps dropped);
* repetitions 1 and no repetition axes: the kernel spans the whole map.

Examples
--------
>>> import numpy as np
>>> from compiler.snn.network import Population
>>> b = Population(id="b", shape={"r": 4})
>>> k = StencilProjection(id="k", source="b", target="b", axes=("r",), kernel=np.ones(3),
...                       edge=("clip",))
>>> k.repetitions(b), k.n_synapse_instances(b, b), k.wired_synapses(b, b)
(1, 12, 10)
>>> k.repetition_axes(b) is None, k.tap_offsets().ravel().tolist()
(True, [-1, 0, 1])
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from compiler.snn.projection_checks import finite_weights as _finite_weights
from compiler.snn.projection_checks import int_delays as _int_delays
from ir.errors import NetworkError

if TYPE_CHECKING:
    from compiler.snn.network import Population

__all__ = ["EdgeMode", "StencilProjection"]

EdgeMode = Literal["wrap", "clip"]


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

    # ------------------------------------------------------------ projection protocol
    def stored_weights(self) -> np.ndarray:
        """The stored weight array: the kernel."""
        return self.kernel

    def with_weights(self, w: np.ndarray) -> StencilProjection:
        """This projection with its kernel replaced."""
        return replace(self, kernel=w)

    def min_delay(self) -> int | None:
        """The smallest delay of a live (non-zero) tap; ``None`` when no tap is live.

        Examples
        --------
        >>> import numpy as np
        >>> StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                   kernel=np.array([0.0, 1.0, 1.0]), edge=("clip",),
        ...                   delays=np.array([0, 3, 1])).min_delay()
        1
        """
        live = self.kernel != 0
        if not live.any():
            return None
        return 0 if self.delays is None else int(self.delays[live].min())

    def repetitions(self, src: Population) -> int:
        """1: the kernel is one instance spanning the whole map."""
        return 1

    def repetition_axes(self, tgt: Population) -> None:
        """``None``: a stencil is not shared over repetition axes."""
        return None

    def n_synapse_instances(self, src: Population, tgt: Population) -> int:
        r"""Nominal synapse instances :math:`|T| \cdot \mathrm{nnz}(K)` (clipped taps counted)."""
        return tgt.size * self.n_taps

    def wired_synapses(self, src: Population, tgt: Population) -> int:
        """Synapses at every target position, taps off a ``clip`` edge excluded."""
        deg = self.degree_map(tgt, incoming=True)
        return int(deg.sum()) * (tgt.size // deg.size)

    def tap_offsets(self) -> np.ndarray:
        """``(n_taps, n_axes)`` offsets ``o`` of the non-zero taps, centred, in kernel order."""
        return np.argwhere(self.kernel != 0) - np.array(self.radius)

    def degree_map(self, pop: Population, *, incoming: bool) -> np.ndarray:
        r"""Synapses per neuron over the map axes (in ``axes`` order).

        ``incoming``: :math:`\sum_o [K_o \ne 0]\,[x + o \in \text{map}]` (taps a target
        neuron receives); otherwise :math:`\sum_o [K_o \ne 0]\,[x - o \in \text{map}]`
        (targets a source neuron reaches).  ``wrap`` axes never lose a tap.

        Examples
        --------
        >>> import numpy as np
        >>> from compiler.snn.network import Population
        >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
        ...                       kernel=np.array([1.0, 1.0, 1.0]), edge=("clip",))
        >>> k.degree_map(Population(id="b", shape={"r": 4}), incoming=True).tolist()
        [2, 3, 3, 2]
        """
        mask = (self.kernel != 0).astype(np.float64)
        inside = np.ones([pop.shape[a] for a in self.axes])
        pad = [(r, r) for r in self.radius]
        for ax, (edge, width) in enumerate(zip(self.edge, pad, strict=True)):
            widths = [(0, 0)] * inside.ndim
            widths[ax] = width
            inside = np.pad(inside, widths, mode="wrap" if edge == "wrap" else "constant")
        from scipy import signal  # imported here: scipy.signal takes ~1 s to import

        op = signal.correlate if incoming else signal.convolve
        return np.rint(op(inside, mask, mode="valid")).astype(np.int64)

    def check_axes(self, src: Population, tgt: Population) -> None:
        """Raise :class:`~ir.errors.NetworkError` unless ``src`` and ``tgt`` fit the kernel."""
        pid = self.id
        if src.shape != tgt.shape:  # same axes and sizes; matched by name, in any order
            raise NetworkError(f"projection {pid!r}: a stencil needs the same axes and sizes "
                               f"on source and target, got {src.shape} and {tgt.shape}",
                               node=pid)
        for axis, width in zip(self.axes, self.kernel.shape, strict=True):
            if axis not in src.shape:
                raise NetworkError(f"projection {pid!r}: axis {axis!r} is not in population "
                                   f"{src.id!r} (axes {src.axes})", node=pid)
            if width > src.shape[axis] and self.edge[self.axes.index(axis)] == "wrap":
                raise NetworkError(f"projection {pid!r}: kernel width {width} exceeds axis "
                                   f"{axis!r} of size {src.shape[axis]} with wrap edges",
                                   node=pid)
