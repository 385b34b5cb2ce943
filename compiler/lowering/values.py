"""What a lowered IR node's value is: an array on the host, or a population's spikes.

A :class:`SpikeValue` is the contract between lowering rules.  Its population
has exactly the IR value's axes, in the IR order, plus a trailing ``part`` axis
when the value is split over several neurons (±Re, ±Im …); ``decoder`` says how
to read the IR value back from the spikes (the same fields as
:class:`compiler.snn.Decoder`), and ``window`` is the range of steps
``[start, end)`` in which the population spikes.  ``code`` carries what a
downstream motif needs to consume the spikes directly (for time codes: the
value ↔ spike-step map), as plain JSON-able data.

Examples
--------
>>> from ir.types import TensorType
>>> t = TensorType(axes={"range": 8})
>>> HostValue(node="x", type=t).on_host
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from compiler.snn import Decoder
from ir.types import TensorType

__all__ = ["HostValue", "SpikeValue", "Value"]


@dataclass(frozen=True)
class HostValue:
    """The value of IR node ``node`` is a numpy array on the host."""

    node: str
    type: TensorType

    @property
    def on_host(self) -> bool:
        """Always True."""
        return True


@dataclass(frozen=True)
class SpikeValue:
    """The value of IR node ``node`` is carried by the spikes of ``population``.

    Parameters
    ----------
    node : str
        The IR node whose value this is.
    type : TensorType
        Its IR type (the population's axes are ``type.axes`` [+ ``part``]).
    population : str
        Population id in the network being built (``network`` tells which).
    decoder : Decoder
        How to read the value (its ``port`` is the node id).
    window : tuple of int
        ``[start, end)`` steps in which the population may spike.
    code : dict
        Motif-specific description for consumers reading spikes directly.
    network : int
        Index of the spiking segment that holds the population.
    """

    node: str
    type: TensorType
    population: str
    decoder: Decoder
    window: tuple[int, int]
    code: dict[str, Any] = field(default_factory=dict)
    network: int = 0

    @property
    def on_host(self) -> bool:
        """Always False."""
        return False


Value = HostValue | SpikeValue
