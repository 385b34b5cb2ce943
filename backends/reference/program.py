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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from backends.reference.plan import SimPlan, build_plan
from backends.reference.result import SimResult
from backends.reference.simulate import simulate
from compiler.program import CompiledProgram
from ir.errors import SimulationError
from ir.evaluate import EVAL_REGISTRY, check_input

__all__ = ["ProgramResult", "program_plans", "run_program"]


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

    @property
    def spike_counts(self) -> dict[str, int]:
        """Spikes per population of every spiking segment (population ids are unique)."""
        return {k: v for s in self.simulations for k, v in s.spike_counts.items()}

    @property
    def synaptic_events(self) -> dict[str, int]:
        """Synaptic events per projection of every spiking segment."""
        return {k: v for s in self.simulations for k, v in s.synaptic_events.items()}

    @property
    def total_spikes(self) -> int:
        """Spikes of every population of every segment."""
        return sum(s.total_spikes for s in self.simulations)

    @property
    def total_synaptic_events(self) -> int:
        """Synaptic events of every projection of every segment."""
        return sum(s.total_synaptic_events for s in self.simulations)

    @property
    def mode(self) -> str:
        """The engines that ran, e.g. ``"closed"`` or ``"closed+step"`` (``"host"`` if none)."""
        return "+".join(dict.fromkeys(s.mode for s in self.simulations)) or "host"

    def summary(self) -> str:
        """A short report: per spiking segment its :meth:`SimResult.summary`, then the outputs."""
        lines = [f"program run: {len(self.simulations)} spiking segment(s), mode={self.mode}, "
                 f"spikes={self.total_spikes} synaptic_events={self.total_synaptic_events}"]
        for i, s in enumerate(self.simulations):
            lines.append(f"segment {i}: " + s.summary().replace("\n", "\n  "))
        lines += [f"output {k}: shape {v.shape}" for k, v in self.outputs.items()]
        return "\n".join(lines)


def program_plans(program: CompiledProgram, arithmetic: str = "float64") -> list[SimPlan]:
    """One :class:`SimPlan` per spiking segment, to reuse over many frames with ``plans=``.

    Building a plan (index maps, stencil edges, delay classes) costs about as much
    as simulating one frame in closed form; a caller running many frames builds
    the plans once.
    """
    return [build_plan(net, arithmetic) for net in program.networks]


def run_program(program: CompiledProgram, inputs: Mapping[str, np.ndarray], *,
                mode: str = "auto", arithmetic: str = "float64", record_spikes: bool = False,
                plans: Sequence[SimPlan] | None = None) -> ProgramResult:
    """Run every segment of ``program`` on ``inputs`` (one array per graph input node).

    Parameters
    ----------
    program : CompiledProgram
        What :func:`compiler.compile.compile_graph` returned.
    inputs : mapping of str to ndarray
        One array per input node id, of the node's declared shape.
    mode, arithmetic : str
        Passed to :func:`backends.reference.simulate` for every spiking segment.
    record_spikes : bool
        Keep spike rasters (see :func:`~backends.reference.simulate`).
    plans : sequence of SimPlan, optional
        :func:`program_plans` of this program, built once for many runs.

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
    if plans is not None and len(plans) != len(program.networks):
        raise SimulationError(f"program {graph.name!r}: {len(plans)} plans given for "
                              f"{len(program.networks)} spiking segments; use program_plans()")
    for seg in program.segments:
        if seg.kind == "spiking":
            plan = None if plans is None else plans[len(sims)]
            result = simulate(seg.network, {p: values[p] for p in seg.inputs}, mode=mode,
                              arithmetic=arithmetic, record_spikes=record_spikes, plan=plan)
            # a decoded mask (0/1 from spikes) is a boolean array, like the interpreter's
            values.update({k: (np.asarray(v) != 0) if types[k].domain == "mask" else v
                           for k, v in result.outputs.items()})
            sims.append(result)
        else:
            op = graph.op(seg.node)
            args = [values[i] for i in seg.inputs]
            values[seg.node] = EVAL_REGISTRY[type(op)](seg.node, op, args,
                                                       [types[i] for i in seg.inputs])
    outputs = {k: values[k] for k in graph.output_ids()}
    return ProgramResult(values=values, outputs=outputs, simulations=sims)
