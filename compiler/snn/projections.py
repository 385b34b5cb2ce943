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

Each kind answers for itself through the **projection protocol**
:class:`ProjectionKind` — its stored weights and a copy with new ones, its
smallest live delay, its repetitions and repetition axes, its nominal and
wired synapse counts, its axis checks — so no caller asks which kind it holds.
The kinds live in :mod:`compiler.snn.matrix_projection` and
:mod:`compiler.snn.stencil_projection`; this module gathers them.  Layers above
the compile path that need per-kind code of their own (the simulator's
deliveries, the Brian2 and NIR expansions, the NumPy emitter, the hardware
counting) keep an explicit table keyed by the projection *type*
(``{MatrixProjection: …, StencilProjection: …}``), built at import without side
effects; no ``isinstance`` ladder and no ``kind ==`` test
(``tests/test_projection_protocol.py`` walks the source to keep it so).  The
``kind`` field stays as the serialized tag of an artifact.

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

from typing import Protocol, runtime_checkable

import numpy as np

from compiler.snn.matrix_projection import MatrixProjection
from compiler.snn.stencil_projection import EdgeMode, StencilProjection

__all__ = ["MatrixProjection", "StencilProjection", "Projection", "ProjectionKind", "EdgeMode",
           "PROTOCOL", "weights_of", "with_weights"]

Projection = MatrixProjection | StencilProjection

#: The members every projection kind implements (checked by the tests).
PROTOCOL: tuple[str, ...] = (
    "id", "source", "target", "delays", "origin", "kind", "n_synapses", "max_delay", "by_delay",
    "stored_weights", "with_weights", "min_delay", "repetitions", "repetition_axes",
    "n_synapse_instances", "wired_synapses", "check_axes",
)


@runtime_checkable
class ProjectionKind(Protocol):
    """What every projection kind answers for itself (see the module docstring).

    Attributes
    ----------
    id, source, target : str
        Projection id and its population ids.
    delays : ndarray of int or None
        Per-synapse delays, shaped like :meth:`stored_weights`.
    origin : dict
        Provenance (``node``, ``motif``).
    kind : str
        The serialized tag (``"matrix"``, ``"stencil"``); not for dispatch.
    n_synapses : int
        Stored synapses (shared weights once).
    max_delay : int
        The largest delay in steps.
    """

    id: str
    source: str
    target: str
    delays: np.ndarray | None
    origin: dict[str, str]
    kind: str

    @property
    def n_synapses(self) -> int: ...

    @property
    def max_delay(self) -> int: ...

    def by_delay(self) -> dict:
        """The stored weights split by delay class."""

    def stored_weights(self) -> np.ndarray:
        """The stored weight array (what quantization scales)."""

    def with_weights(self, w: np.ndarray) -> ProjectionKind:
        """A copy with the stored weight array replaced."""

    def min_delay(self) -> int | None:
        """The smallest delay of a live synapse (``None``: none is live)."""

    def repetitions(self, src) -> int:
        """How many times the stored weights are instantiated as one motif."""

    def repetition_axes(self, tgt) -> set[str] | None:
        """Target axes the weights are shared over (``None``: not shared over axes)."""

    def n_synapse_instances(self, src, tgt) -> int:
        """Nominal synapse instances (every repetition and position, edges ignored)."""

    def wired_synapses(self, src, tgt) -> int:
        """Distinct synapses a chip wires (clipped stencil taps excluded)."""

    def check_axes(self, src, tgt) -> None:
        """Raise :class:`~ir.errors.NetworkError` unless the populations fit."""


def weights_of(p: Projection) -> np.ndarray:
    """The stored weight array of a projection (:meth:`ProjectionKind.stored_weights`).

    Examples
    --------
    >>> weights_of(StencilProjection(id="s", source="a", target="b", axes=("i",),
    ...                              kernel=np.array([1.0, -1.0, 0.5]), edge=("clip",))).tolist()
    [1.0, -1.0, 0.5]
    """
    return p.stored_weights()


def with_weights(p: Projection, w: np.ndarray) -> Projection:
    """``p`` with its stored weight array replaced (:meth:`ProjectionKind.with_weights`)."""
    return p.with_weights(w)
