"""Run a :class:`~compiler.program.CompiledProgram`: its spiking and host segments in order.

Values flow between segments by radar-IR node id: a spiking segment's encoder
ports read values, its decoder ports produce them; a host segment evaluates
its node with the reference interpreter's implementation (the conventional
numpy meaning, :data:`ir.evaluate.EVAL_REGISTRY`).

Examples
--------
>>> import numpy as np
>>> from compiler.compile import compile_graph
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 3}},
...     {"id": "m", "op": "magnitude", "input": "a", "kind": "square"},
...     {"id": "o", "op": "output", "input": "m"}]})
>>> run_program(compile_graph(g), {"a": np.array([1.0, -2.0, 3.0])}).outputs["o"].tolist()
[1.0, 4.0, 9.0]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from backends.reference.result import SimResult
from backends.reference.simulate import simulate
from compiler.program import CompiledProgram
from ir.errors import SimulationError
from ir.evaluate import EVAL_REGISTRY, check_input

__all__ = ["ProgramResult", "run_program"]


@dataclass(frozen=True)
class ProgramResult:
    """Values of every IR node a program computed, and each spiking segment's result.

    Attributes
    ----------
    values : dict of str to ndarray
        Every node's value (inputs, decoded spiking outputs, host results).
    outputs : dict of str to ndarray
        The values of the graph's ``output`` nodes.
    simulations : list of SimResult
        One per spiking segment, in order (spike and synaptic-event counts).
    """

    values: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    simulations: list[SimResult] = field(default_factory=list)


def run_program(program: CompiledProgram, inputs: Mapping[str, np.ndarray], *,
                mode: str = "auto", arithmetic: str = "float64") -> ProgramResult:
    """Run every segment of ``program`` on ``inputs`` (one array per graph input node).

    Parameters
    ----------
    program : CompiledProgram
        What :func:`compiler.compile.compile_graph` returned.
    inputs : mapping of str to ndarray
        One array per input node id, of the node's declared shape.
    mode, arithmetic : str
        Passed to :func:`backends.reference.simulate` for every spiking segment.

    Raises
    ------
    SimulationError
        Missing or unknown inputs, or a segment that cannot run.
    """
    graph = program.graph
    types = graph.infer_types()
    expected = set(graph.input_ids())
    missing, extra = expected - set(inputs), set(inputs) - expected
    if missing or extra:
        raise SimulationError(f"program {graph.name!r}: inputs {sorted(inputs)} do not match the "
                              f"graph's input nodes {sorted(expected)} (missing "
                              f"{sorted(missing)}, unknown {sorted(extra)})")
    values = {k: check_input(k, types[k], v) for k, v in inputs.items()}
    sims = []
    for seg in program.segments:
        if seg.kind == "spiking":
            result = simulate(seg.network, {p: values[p] for p in seg.inputs}, mode=mode,
                              arithmetic=arithmetic)
            values.update(result.outputs)
            sims.append(result)
        else:
            op = graph.op(seg.node)
            args = [values[i] for i in seg.inputs]
            values[seg.node] = EVAL_REGISTRY[type(op)](seg.node, op, args,
                                                       [types[i] for i in seg.inputs])
    outputs = {k: values[k] for k in graph.output_ids()}
    return ProgramResult(values=values, outputs=outputs, simulations=sims)
