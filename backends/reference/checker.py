"""The reference simulator as the compiler's :class:`~compiler.accuracy.simulator.Simulator`.

``compile_graph(..., simulator=ReferenceSimulator())`` measures the accuracy contract
with :func:`backends.reference.run_program`: values beyond an encoder's range are
clipped (and counted: a clipped input is a figure of the contract, not an error).

Examples
--------
>>> from compiler.accuracy.simulator import Simulator
>>> isinstance(ReferenceSimulator(), Simulator), ReferenceSimulator().name
(True, 'reference')
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from backends.reference.program import run_program
from compiler.accuracy.simulator import SimulatedFrames

__all__ = ["ReferenceSimulator"]


class ReferenceSimulator:
    """Run programs on the reference simulator (closed form where it applies).

    Parameters
    ----------
    mode : {"auto", "closed", "step"}
        The engine (:func:`backends.reference.run_program`).
    max_time_s : float or None
        The simulator's time guard per run.
    """

    name = "reference"

    def __init__(self, mode: str = "auto", max_time_s: float | None = None) -> None:
        self.mode = mode
        self.max_time_s = max_time_s

    def run(self, program, inputs: Mapping[str, np.ndarray]) -> SimulatedFrames:
        """Every node's value and the clipped counts per encoder port."""
        res = run_program(program, inputs, mode=self.mode, out_of_range="clip",
                          max_time_s=self.max_time_s)
        return SimulatedFrames(values=res.values, clipped=res.clipped,
                               simulations=tuple(res.simulations))
