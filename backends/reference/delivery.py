r"""Spike delivery: how a batch of spike events becomes input current, per projection kind.

A *delivery* is the simulator's precomputed plan of one projection.  Its
``current(k, events, n_batch, values=None)`` takes spike *events* — flat
indices into a ``(n_batch, *source_shape)`` array, ascending — and returns the
current they produce as a ``(n_batch, *target_shape)`` array, for delay class
``k`` (``delays[k]`` steps).  The batch axis is the frames in step mode and
``steps × frames`` in the closed form, so both engines run the very same
arithmetic.  ``n_events(k, events)`` counts the synaptic events (each spike
times the synapses it reaches); ``weight_nbytes`` is the weight memory.

Kinds: :class:`~backends.reference.matrix.MatrixDelivery` (shared matrix along
named axes) and :class:`~backends.reference.stencil.StencilDelivery` (kernel
correlation), built from a projection's ``kind`` through the explicit
registry :data:`DELIVERY_BUILDERS`.
"""

from __future__ import annotations

from collections.abc import Callable

from backends.reference.matrix import MatrixDelivery
from backends.reference.stencil import StencilDelivery

__all__ = ["MatrixDelivery", "StencilDelivery", "Delivery", "DELIVERY_BUILDERS"]

Delivery = MatrixDelivery | StencilDelivery

#: Delivery builders by projection ``kind``: ``(projection, source, target, integer) -> delivery``.
DELIVERY_BUILDERS: dict[str, Callable[..., Delivery]] = {
    "matrix": MatrixDelivery.build,
    "stencil": StencilDelivery.build,
}
