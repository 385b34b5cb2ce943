"""Run a program on check frames and measure its contract (:mod:`compiler.accuracy.contract`).

Examples
--------
>>> import numpy as np
>>> from compiler.accuracy.simulator import SimulatedFrames
>>> from compiler.compile import compile_graph
>>> from ir import Graph, evaluate
>>> g = Graph.from_dict({"name": "r", "nodes": [
...     {"id": "x", "op": "input", "shape": {"sample": 16}},
...     {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> x = np.random.default_rng(0).normal(size=(2, 16))
>>> class Exact:  # a stand-in simulator that returns the golden values
...     name = "exact"
...     def run(self, program, inputs):
...         return SimulatedFrames(values=evaluate(program.graph, inputs))
>>> c = check_program(compile_graph(g, None, calibration_inputs={"x": x}), {"x": x}, Exact())
>>> c.holds, [s.node for s in c.stages]
(True, ['f'])
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from compiler.accuracy.contract import Contract, Tolerances, measure_contract
from compiler.accuracy.simulator import SimulatedFrames, Simulator
from ir.frames import n_frames
from ir.interpreter import evaluate

__all__ = ["check_program"]


def check_program(program, inputs: Mapping[str, np.ndarray], simulator: Simulator, *,
                  tolerances: Tolerances | None = None, held_out: bool = True,
                  note: str = "", run: SimulatedFrames | None = None) -> Contract:
    """The contract of ``program`` measured by ``simulator`` on ``inputs`` against the golden chain.

    Parameters
    ----------
    program : CompiledProgram
        The compiled chain.
    inputs : mapping of str to ndarray
        Check frames by input node id (one frame, or a leading frames axis).
    simulator : Simulator
        Runs the program (:class:`compiler.accuracy.simulator.Simulator`).
    tolerances : Tolerances, optional
        The contract.
    held_out, note : bool, str
        Whether the frames were held back from calibration; a remark for the summary.
    run : SimulatedFrames, optional
        ``simulator.run(program, inputs)`` when the caller already ran it (to keep its
        spike counts); default: run it here.

    Returns
    -------
    Contract
    """
    graph = program.graph
    count = n_frames(graph.infer_types(), inputs, f"program {graph.name!r}")
    run = simulator.run(program, inputs) if run is None else run
    reference = evaluate(graph, inputs, registry=program.evaluators)
    overflow = {k: v for sim in run.simulations
                for k, v in (getattr(sim, "state_overflow", None) or {}).items()}
    return measure_contract(program, run.values, reference, run.clipped, n_frames=count or 1,
                            framed=count is not None, tolerances=tolerances,
                            held_out=held_out, note=note, overflow=overflow)
