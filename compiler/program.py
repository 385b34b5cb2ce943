"""What compilation produces: a :class:`CompiledProgram` of spiking and host segments.

A radar chain rarely runs entirely on spikes: inputs arrive as arrays, some
ops (clustering, tracking, or a magnitude the user keeps on the host) run in
numpy.  The compiler therefore cuts the graph into **segments**, run in
order, that exchange values by radar-IR node id:

* a *spiking* segment is one :class:`~compiler.snn.SpikingNetwork`; its encoder
  ports are the ids of the IR nodes whose values it reads, its decoder ports the
  ids of the IR nodes whose values it produces;
* a *host* segment evaluates one IR node with the reference interpreter's
  implementation of its op (the conventional numpy meaning).

Every boundary between the two is explicit, so the report can state its
bandwidth.

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 4}},
...     {"id": "o", "op": "output", "input": "a"}]})
>>> p = CompiledProgram(graph=g)
>>> p.networks, dict(p.records), p.records.report is None
([], {}, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from compiler.hardware.profile import HardwareProfile
from compiler.program_records import ProgramRecords
from compiler.snn import SpikingNetwork
from ir import Graph

__all__ = ["Segment", "CompiledProgram"]


@dataclass
class Segment:
    """One step of a compiled program.

    Parameters
    ----------
    kind : {"spiking", "host"}
        A spiking network, or one IR node evaluated on the host.
    inputs : list of str
        IR node ids whose values the segment reads.
    outputs : list of str
        IR node ids whose values the segment produces.
    network : SpikingNetwork, optional
        The network of a spiking segment.
    node : str, optional
        The IR node of a host segment.
    """

    kind: Literal["spiking", "host"]
    inputs: list[str]
    outputs: list[str]
    network: SpikingNetwork | None = None
    node: str | None = None


@dataclass
class CompiledProgram:
    """A compiled chain: the (rewritten) graph, its segments, and every pass's record.

    Parameters
    ----------
    graph : ir.Graph
        The graph as the passes left it (e.g. windows folded into DFTs).
    segments : list of Segment
        Spiking and host segments in execution order.
    options : dict
        The compile options used (JSON-able).
    records : ProgramRecords
        What the passes recorded, as typed fields (``records.calibration``,
        ``records.motifs``, ``records.quantization``, ``records.splits``,
        ``records.placement``, ``records.report``, ``records.timings`` …;
        :mod:`compiler.program_records`); a mapping by pass name given here is
        converted.
    target : HardwareProfile or None
        The hardware profile compiled for, loaded (None: compiled without a target — no
        allocation passes; the lowering read :data:`~compiler.hardware.NO_TARGET`).
    evaluators : dict, optional
        Reference implementations (op class → function) of ops the built-in
        ``ir.EVAL_REGISTRY`` lacks, given to ``compile_graph(..., evaluators=)``:
        the host segments run with them.  Code, not data: never saved in an
        artifact (a loaded program knows the built-in ops only).
    calibration_policy : {"static", "per-input"}
        The calibration policy compiled with (set by ``compile_graph`` and by
        :func:`backends.load_program` from the stored options).
    """

    graph: Graph
    segments: list[Segment] = field(default_factory=list)
    options: dict[str, Any] = field(default_factory=dict)
    records: ProgramRecords = field(default_factory=ProgramRecords)
    target: HardwareProfile | None = None
    evaluators: dict[type, Any] = field(default_factory=dict)
    calibration_policy: Literal["static", "per-input"] = "static"

    def __post_init__(self) -> None:
        if not isinstance(self.records, ProgramRecords):  # a mapping by pass name
            given, self.records = dict(self.records), ProgramRecords()
            self.records.update(given)

    @property
    def sized_for(self) -> HardwareProfile:
        """The profile the report sizes the program against: its target, or the built-in
        ``unbounded`` profile (no budgets) for a program compiled without one.

        Examples
        --------
        >>> from ir import Graph
        >>> g = Graph.from_dict({"name": "x", "nodes": [
        ...     {"id": "a", "op": "input", "shape": {"range": 4}},
        ...     {"id": "o", "op": "output", "input": "a"}]})
        >>> CompiledProgram(graph=g).sized_for.name
        'unbounded'
        """
        if self.target is not None:
            return self.target
        from compiler.hardware.loading import load_profile  # the package imports programs' parts

        return load_profile("unbounded")

    @property
    def networks(self) -> list[SpikingNetwork]:
        """The spiking segments' networks, in execution order."""
        return [s.network for s in self.segments if s.kind == "spiking"]

    @property
    def host_nodes(self) -> list[str]:
        """IR nodes evaluated on the host."""
        return [s.node for s in self.segments if s.kind == "host"]

    def segment_of(self, node: str) -> Segment | None:
        """The segment that produces ``node``'s value, or None for a graph input."""
        for seg in self.segments:
            if node in seg.outputs:
                return seg
        return None
