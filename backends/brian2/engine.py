"""Brian2 as a segment engine: :func:`backends.reference.run_program` on Brian2.

``run_program(program, inputs, engine=Brian2Engine())`` evaluates the host nodes as
always and simulates every spiking segment with :func:`~backends.brian2.simulate_brian2`
(the options' ``record_spikes`` and ``out_of_range``; the reference's ``mode``,
``arithmetic``, plans and limits do not apply). On quantized networks (exact current
sums) the outputs equal the reference step engine's (``tests/test_brian2_engine.py``).

Examples
--------
>>> from backends.reference.engine import SegmentEngine
>>> isinstance(Brian2Engine(), SegmentEngine), Brian2Engine("cython").name
(True, 'brian2-cython')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from backends.brian2.run import TARGETS, simulate_brian2
from backends.reference.plan import SimPlan
from backends.reference.result import SimResult
from backends.reference.run_options import RunOptions
from compiler.snn import SpikingNetwork
from ir.errors import SimulationError

__all__ = ["Brian2Engine"]


@dataclass(frozen=True)
class Brian2Engine:
    """Run each spiking segment in Brian2 with code-generation ``target``."""

    target: str = "numpy"

    def __post_init__(self) -> None:
        if self.target not in TARGETS:
            raise SimulationError(f"Brian2Engine(target={self.target!r}): not one of {TARGETS}")

    @property
    def name(self) -> str:
        """``brian2-<target>``, as :attr:`SimResult.mode` says."""
        return f"brian2-{self.target}"

    def simulate(self, network: SpikingNetwork, inputs: Mapping[str, np.ndarray], *,
                 options: RunOptions, plan: SimPlan | None = None) -> SimResult:
        """:func:`simulate_brian2` of ``network`` (``plan`` is the reference's: unused)."""
        return simulate_brian2(network, inputs, target=self.target,
                               record_spikes=options.record_spikes,
                               out_of_range=options.out_of_range)
