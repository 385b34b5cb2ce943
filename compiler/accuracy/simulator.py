"""What the compiler needs of a simulator to measure a program: the :class:`Simulator` protocol.

The compile path cannot import a backend (the layers go one way), so whoever calls
:func:`compiler.compile.compile_graph` hands it one — :class:`radarsnn.compile_graph
<radarsnn>` and the CLI pass the reference simulator
(:class:`backends.reference.ReferenceSimulator`); a chip's own runtime can be passed the
same way.

Examples
--------
>>> import numpy as np
>>> class Echo:
...     name = "echo"
...     def run(self, program, inputs):
...         return SimulatedFrames(values=dict(inputs), clipped={})
>>> isinstance(Echo(), Simulator)
True
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["SimulatedFrames", "Simulator"]


@dataclass(frozen=True)
class SimulatedFrames:
    """Every node's value on the frames run, and the values clipped per encoder port.

    ``simulations`` (optional): one result per spiking segment with ``spike_counts``,
    ``synaptic_events`` (per population / projection, summed over the frames) and
    ``n_frames``; the resource report's energy then rests on measured counts.
    """

    values: Mapping[str, np.ndarray]
    clipped: Mapping[str, int] = field(default_factory=dict)
    simulations: Sequence[Any] = ()


@runtime_checkable
class Simulator(Protocol):
    """Runs a compiled program on inputs (one frame, or a leading frames axis)."""

    name: str

    def run(self, program: Any, inputs: Mapping[str, np.ndarray]) -> SimulatedFrames:
        """Every node's value (decoded spiking outputs included) and the clipped counts."""
        ...
