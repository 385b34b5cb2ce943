"""What :func:`~backends.reference.program.run_program` needs of a simulator: a segment engine.

A compiled program alternates spiking segments (one :class:`~compiler.snn.SpikingNetwork`
each) and host nodes. ``run_program`` evaluates the host nodes itself and hands every
spiking segment to an engine — anything with a ``name`` and
``simulate(network, inputs, *, options, plan)`` returning a
:class:`~backends.reference.result.SimResult` (decoded ``outputs`` by decoder port, spike
and synaptic-event counts, clipped inputs). The reference simulator is the default
(:data:`REFERENCE`); :class:`backends.brian2.Brian2Engine` runs the same program in Brian2,
and a chip's runtime can be wrapped the same way.

Examples
--------
>>> import numpy as np
>>> from compiler.snn.examples import tiny_network
>>> net = tiny_network()
>>> isinstance(REFERENCE, SegmentEngine), REFERENCE.name
(True, 'reference')
>>> r = REFERENCE.simulate(net, {"x": np.array([1.0, 0.5])}, options=RunOptions(), plan=None)
>>> sorted(r.outputs) == sorted(d.port for d in net.decoders)
True
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np

from backends.reference.plan import SimPlan
from backends.reference.result import SimResult
from backends.reference.run_options import RunOptions
from backends.reference.simulate import simulate
from compiler.snn import SpikingNetwork

__all__ = ["REFERENCE", "ReferenceEngine", "SegmentEngine"]


@runtime_checkable
class SegmentEngine(Protocol):
    """Runs one spiking segment of a program (see the module docstring)."""

    name: str

    def simulate(self, network: SpikingNetwork, inputs: Mapping[str, np.ndarray], *,
                 options: RunOptions, plan: SimPlan | None) -> SimResult:
        """The segment's decoded outputs and counts on ``inputs`` (one frame)."""
        ...


class ReferenceEngine:
    """The reference simulator (:func:`backends.reference.simulate`) as a segment engine:
    ``options`` carries the mode, arithmetic and limits; ``plan`` a prebuilt plan."""

    name = "reference"

    def simulate(self, network: SpikingNetwork, inputs: Mapping[str, np.ndarray], *,
                 options: RunOptions, plan: SimPlan | None) -> SimResult:
        """:func:`backends.reference.simulate` with ``options`` and ``plan``."""
        return simulate(network, inputs, plan=plan, options=options)

    def __repr__(self) -> str:
        return "ReferenceEngine()"


#: The default engine of :func:`~backends.reference.program.run_program`.
REFERENCE = ReferenceEngine()
