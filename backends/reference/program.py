"""Run a :class:`~compiler.program.CompiledProgram`: its spiking and host segments in order.

Values flow between segments by radar-IR node id: a spiking segment's encoder
ports read values, its decoder ports produce them; a host segment evaluates
its node with the reference interpreter's implementation (the conventional
numpy meaning, :data:`ir.interpreter.EVAL_REGISTRY`, plus the implementations of
new ops the program was compiled with, ``program.evaluators``).

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

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from backends.reference.engine import REFERENCE, SegmentEngine
from backends.reference.frames_pool import map_frames_pooled, pool_key
from backends.reference.frames_run import (
    FrameStack,
    SimStack,
    map_frames,
    resolve_parallel,
    resolve_workers,
)
from backends.reference.guards import MAX_MEMORY_BYTES, MAX_TIME_S
from backends.reference.input_range import DEFAULT_POLICY, check_policy
from backends.reference.plan import SimPlan, build_plan
from backends.reference.result import SimResult
from backends.reference.run_options import RunOptions
from backends.reference.units import apply_units, normalize_inputs, normalized_inputs, unit_plan
from compiler.program import CompiledProgram
from ir.errors import SimulationError
from ir.frames import frame, n_frames
from ir.interpreter import check_input, eval_registry, evaluate_node
from ir.limits import check_limit, check_value_sizes
from ir.model import short_repr

__all__ = ["ProgramResult", "check_program", "program_plans", "run_program"]


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
    normalized : list of str
        Under the ``per-input`` policy, the nodes whose values stay in normalised units
        (:mod:`backends.reference.units`: more than one normalised input); every other
        value is in the units of the inputs.
    input_peaks : dict of str to ndarray
        Under ``per-input``, each normalised input's per-slice peak (the factor undone).
    """

    values: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    simulations: list[SimResult] = field(default_factory=list)
    normalized: list[str] = field(default_factory=list)
    input_peaks: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def spike_counts(self) -> dict[str, int]:
        """Spikes per population of every spiking segment (population ids are unique)."""
        return {k: v for s in self.simulations for k, v in s.spike_counts.items()}

    @property
    def synaptic_events(self) -> dict[str, int]:
        """Synaptic events per projection of every spiking segment."""
        return {k: v for s in self.simulations for k, v in s.synaptic_events.items()}

    @property
    def clipped(self) -> dict[str, int]:
        """Per encoder port of every segment, the values clipped to the encoder's range."""
        return {k: v for s in self.simulations for k, v in s.clipped.items()}

    @property
    def state_overflow(self) -> dict[str, int]:
        """Per population of every segment, neuron-steps beyond the chip's state range
        (:attr:`SimResult.state_overflow`)."""
        return {k: v for s in self.simulations for k, v in s.state_overflow.items()}

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


def check_program(program: CompiledProgram) -> None:
    """Check that the segments of ``program`` fit its graph and each other.

    Every segment reads values that exist by then (graph inputs or earlier
    outputs) and produces its own: a host segment exactly its node, from the
    node's inputs; a spiking segment the decoder ports of its network, from its
    encoder ports.  No value is produced twice, and every output node is produced.

    Raises
    ------
    SimulationError
        Naming the segment (by index) and the node or port at fault.

    Examples
    --------
    >>> from compiler.program import Segment
    >>> from compiler.compile import compile_graph
    >>> from ir import Graph
    >>> g = Graph.from_dict({"nodes": [{"id": "a", "op": "input", "shape": {"r": 2}},
    ...                                {"id": "o", "op": "output", "input": "a"}]})
    >>> p = compile_graph(g, target=None)
    >>> check_program(p)
    >>> p.segments = [Segment(kind="host", inputs=["o"], outputs=["o"], node="o")]
    >>> check_program(p)
    Traceback (most recent call last):
    ...
    ir.errors.SimulationError: program 'chain', segment 0 (host 'o'): reads ['o'], but node 'o' \
reads ['a']
    """
    graph = program.graph
    where = f"program {graph.name!r}"
    if not isinstance(program.segments, list):
        raise SimulationError(f"{where}: segments must be a list; got "
                              f"{type(program.segments).__name__}")
    have = set(graph.input_ids())
    for index, seg in enumerate(program.segments):
        kind = getattr(seg, "kind", None)
        at = f"{where}, segment {index} ({kind})"
        if kind == "host":
            at = f"{where}, segment {index} (host {seg.node!r})"
            if seg.node not in graph or graph.op(seg.node).arity == 0:
                raise SimulationError(f"{at}: not a computing node of the graph", node=None)
            if list(seg.inputs) != list(graph.inputs_of(seg.node)):
                raise SimulationError(f"{at}: reads {list(seg.inputs)}, but node {seg.node!r} "
                                      f"reads {list(graph.inputs_of(seg.node))}", node=seg.node)
            if list(seg.outputs) != [seg.node]:
                raise SimulationError(f"{at}: must produce [{seg.node!r}], not "
                                      f"{list(seg.outputs)}", node=seg.node)
        elif kind == "spiking":
            net = seg.network
            ports = sorted(e.port for e in getattr(net, "encoders", []))
            outs = sorted(d.port for d in getattr(net, "decoders", []))
            if sorted(seg.inputs) != ports or sorted(seg.outputs) != outs:
                raise SimulationError(f"{at}: reads {list(seg.inputs)} and produces "
                                      f"{list(seg.outputs)}, but its network's encoder ports are "
                                      f"{ports} and decoder ports {outs}")
            stray = [n for n in (*seg.inputs, *seg.outputs) if n not in graph]
            if stray:
                raise SimulationError(f"{at}: ports {stray} are not nodes of the graph")
        else:
            raise SimulationError(f"{at}: kind must be 'spiking' or 'host'")
        missing = [n for n in seg.inputs if n not in have]
        if missing:
            raise SimulationError(f"{at}: reads {missing} before any segment produces them",
                                  node=missing[0])
        again = [n for n in seg.outputs if n in have]
        if again:
            raise SimulationError(f"{at}: produces {again} a second time", node=again[0])
        have.update(seg.outputs)
    never = [n for n in graph.output_ids() if n not in have]
    if never:
        raise SimulationError(f"{where}: no segment produces the output nodes {never}",
                              node=never[0])


def program_plans(program: CompiledProgram, arithmetic: str = "float64") -> list[SimPlan]:
    """One :class:`SimPlan` per spiking segment, to reuse over many frames with ``plans=``.

    Building a plan (index maps, stencil edges, delay classes) costs about as much
    as simulating one frame in closed form; a caller running many frames builds
    the plans once.
    """
    return [build_plan(net, arithmetic) for net in program.networks]


def run_program(program: CompiledProgram, inputs: Mapping[str, np.ndarray], *,
                mode: str = "auto", arithmetic: str = "float64", record_spikes: bool = False,
                plans: Sequence[SimPlan] | None = None, out_of_range: str = DEFAULT_POLICY,
                max_memory_bytes: int | None = MAX_MEMORY_BYTES,
                max_time_s: float | None = MAX_TIME_S,
                progress: Callable[[int, int], None] | None = None,
                workers: int | None = None, parallel: str = "auto",
                options: RunOptions | None = None,
                engine: SegmentEngine = REFERENCE) -> ProgramResult:
    """Run every segment of ``program`` on ``inputs`` (one array per graph input node).

    Parameters
    ----------
    program : CompiledProgram
        What :func:`compiler.compile.compile_graph` returned.
    inputs : mapping of str to ndarray
        One array per input node id, of the node's declared shape — or every one with
        the same extra leading axis of frames (``(F, *declared)``, :mod:`ir.frames`):
        the frames are run one after the other (plans built once) and every value,
        output and segment result gets the frames axis; equal, bit for bit, to running
        the frames one by one.
    mode, arithmetic : str
        Passed to :func:`backends.reference.simulate` for every spiking segment.
    record_spikes : bool
        Keep spike rasters (see :func:`~backends.reference.simulate`).
    plans : sequence of SimPlan, optional
        :func:`program_plans` of this program, built once for many runs.
    out_of_range : {"reject", "warn", "clip"}
        Policy for values above an encoder's range
        (:mod:`backends.reference.input_range`) where the value comes from the
        caller's inputs through host segments only: refuse them (``reject``, the
        default), clip them with an ``OutOfRangeWarning`` (``warn``), or clip
        them (``clip``; ``radarsnn run --clip``).  Values decoded from an
        upstream spiking segment carry that segment's approximation error, so
        they are always clipped; every clipped value is counted in
        :attr:`ProgramResult.clipped`.
    max_memory_bytes, max_time_s : int, float or None
        Limits on each spiking segment's estimate (see :func:`~backends.reference.simulate`);
        with a frames axis the memory limit is shared by the frames, the time limit
        holds per frame.
    progress : callable, optional
        ``progress(done, total)`` after each frame of a framed run (e.g. a tqdm update).
    workers : int, optional
        Workers that share out the frames of a frames axis (None: one per available core;
        :mod:`backends.reference.frames_run`); the result is the same for any number.
    parallel : {"auto", "threads", "processes"}
        What those workers are (:attr:`RunOptions.parallel`): ``auto`` takes worker
        processes, forked once and kept for this program's next calls
        (:mod:`backends.reference.frames_pool`), where forking is safe, else threads.
    options : RunOptions, optional
        ``mode``, ``arithmetic``, ``record_spikes``, ``out_of_range``,
        ``max_memory_bytes``, ``max_time_s``, ``workers`` and ``parallel`` as one record (it
        replaces those arguments); every spiking segment runs with it
        (:mod:`backends.reference.run_options`).
    engine : SegmentEngine
        What runs each spiking segment (:mod:`backends.reference.engine`): the reference
        simulator by default; e.g. :class:`backends.brian2.Brian2Engine` runs the whole
        program with Brian2 simulating its networks (``plans`` apply to the reference).

    Raises
    ------
    IRError
        An input array of the wrong shape or dtype, or with NaN/Inf (naming the input); a
        host node without an implementation, or whose implementation fails or returns
        the wrong shape (naming the node).
    SimulationError
        Missing or unknown inputs (or a key that is not a string), a value out of an
        encoder's range under ``reject``, an unknown policy, a limit that is not a positive
        finite number or None, or a segment that cannot run.

    Notes
    -----
    A host segment evaluates its node with :func:`ir.interpreter.evaluate_node`, looking
    the op up in :data:`ir.interpreter.EVAL_REGISTRY` plus the evaluators the program
    was compiled with (``compile_graph(..., evaluators=)``, kept in
    ``program.evaluators``), else the op class's own ``evaluate``; a host node whose op
    has none raises
    :class:`~ir.errors.IRError` naming the node and the fix.
    """
    if not isinstance(program, CompiledProgram):
        raise SimulationError(f"run_program(program={short_repr(program)}): takes a "
                              f"CompiledProgram, not {type(program).__name__}; compile one with "
                              "compile_graph (one SpikingNetwork: simulate)")
    where = f"program {program.graph.name!r}"
    if not isinstance(engine, SegmentEngine):
        raise SimulationError(f"{where}: engine={short_repr(engine)} has no name and "
                              "simulate(network, inputs, *, options, plan); give a "
                              "backends.reference.engine.SegmentEngine (default: the reference)")
    if progress is not None and not callable(progress):
        raise SimulationError(f"{where}: progress={short_repr(progress)} is not callable; give "
                              "a function progress(done, total) or None")
    if options is None:
        options = RunOptions(mode=mode, arithmetic=arithmetic, record_spikes=record_spikes,
                             out_of_range=out_of_range, max_memory_bytes=max_memory_bytes,
                             max_time_s=max_time_s, workers=workers, parallel=parallel)
    mode, arithmetic, out_of_range = options.mode, options.arithmetic, options.out_of_range
    max_memory_bytes, max_time_s = options.max_memory_bytes, options.max_time_s
    check_policy(out_of_range, where)
    if not isinstance(inputs, Mapping):
        raise SimulationError(f"{where}: inputs must be a mapping of input node id to array; "
                              f"got {type(inputs).__name__}")
    # the limits checked here too: a program without spiking segments never reaches the guard
    options.checked(where)
    check_program(program)
    graph = program.graph
    types = graph.infer_types()
    expected = set(graph.input_ids())
    odd = [k for k in inputs if not isinstance(k, str)]
    if odd:
        raise SimulationError(f"{where}: input key {short_repr(odd[0])} "
                              f"({type(odd[0]).__name__}) is not an input node id; key the "
                              f"arrays by the graph's input ids {sorted(expected)}")
    missing, extra = expected - set(inputs), set(inputs) - expected
    if missing or extra:
        raise SimulationError(f"program {graph.name!r}: inputs {sorted(inputs)} do not match the "
                              f"graph's input nodes {sorted(expected)} (missing "
                              f"{sorted(missing)}, unknown {sorted(extra)})")
    count = n_frames(types, inputs, where)
    if count is not None:
        return _run_frames(program, inputs, count, progress, options,
                           plans=list(plans) if plans is not None else None, engine=engine)
    # every node's value is kept: refuse what cannot fit before the first is allocated
    check_value_sizes(graph, types, types, max_memory_bytes=check_limit(
        "max_memory_bytes", max_memory_bytes, "bytes", where=where), error=SimulationError,
        doing="running the program")
    values = {k: check_input(k, types[k], v) for k, v in inputs.items()}
    per_input = normalized_inputs(program)  # the per-input policy: run as calibrated
    values, peaks = normalize_inputs(values, per_input, {k: types[k].names for k in per_input})
    impls = eval_registry(program.evaluators)
    decoded: set[str] = set()  # nodes whose value went through a spiking segment's decoder
    sims = []
    if plans is not None and len(plans) != len(program.networks):
        raise SimulationError(f"program {graph.name!r}: {len(plans)} plans given for "
                              f"{len(program.networks)} spiking segments; use program_plans()")
    for seg in program.segments:
        if seg.kind == "spiking":
            plan = None if plans is None else plans[len(sims)]
            policy = {p: "clip" if p in decoded else out_of_range for p in seg.inputs}
            result = engine.simulate(seg.network, {p: values[p] for p in seg.inputs},
                                     options=replace(options, out_of_range=policy), plan=plan)
            decoded.update(result.outputs)
            # a decoded mask (0/1 from spikes) is a boolean array, like the interpreter's
            values.update({k: (np.asarray(v) != 0) if types[k].domain == "mask" else v
                           for k, v in result.outputs.items()})
            sims.append(result)
        else:
            values[seg.node] = evaluate_node(seg.node, graph.op(seg.node),
                                             [values[i] for i in seg.inputs],
                                             [types[i] for i in seg.inputs], types[seg.node],
                                             impls)
            if decoded.intersection(seg.inputs):
                decoded.add(seg.node)
    plan, left = unit_plan(program, types, list(values))
    values = apply_units(values, peaks, plan)
    outputs = {k: values[k] for k in graph.output_ids()}
    return ProgramResult(values=values, outputs=outputs, simulations=sims, normalized=left,
                         input_peaks=peaks)


def _run_frames(program: CompiledProgram, inputs: Mapping[str, np.ndarray], count: int,
                progress: Callable[[int, int], None] | None, options: RunOptions, *,
                plans: list[SimPlan] | None, engine: SegmentEngine) -> ProgramResult:
    """:func:`run_program` frame by frame on ``options.workers`` processes or threads, into
    stacked values (:mod:`backends.reference.frames_run`, :mod:`~.frames_pool`)."""
    limit = options.max_memory_bytes
    per_frame = replace(options, max_memory_bytes=None if limit is None else
                        max(1, int(limit) // count), workers=1)
    where = f"program {program.graph.name!r}"
    workers = resolve_workers(options.workers, count)
    rows_made: list = []  # shared stacks the worker processes write rows into (frames_rows)

    def adopt(value: np.ndarray) -> np.ndarray | None:
        return next((s for rows in rows_made if (s := rows.stack_of(value)) is not None), None)

    values, peaks, sims = (FrameStack(count, adopt), FrameStack(count, adopt),
                           SimStack(count, adopt))
    normalized: list[list[str]] = [[]]

    def run_one(frame_inputs: Mapping[str, np.ndarray], frame_options: RunOptions
                ) -> ProgramResult:
        return run_program(program, frame_inputs, plans=plans, options=frame_options,
                           engine=engine)

    def store(i: int, result: ProgramResult) -> None:
        values.put(i, result.values, where=where)
        if result.input_peaks:
            peaks.put(i, result.input_peaks, where=where)
        sims.put(i, result.simulations, where=where, values=result.values)
        if i == 0:
            normalized[0] = result.normalized

    def inputs_of(i: int) -> dict[str, np.ndarray]:
        return frame(inputs, i)

    kind = resolve_parallel(options.parallel, workers, program)
    if kind != "processes" or not map_frames_pooled(
            program, pool_key(program, engine, plans), run_one, count, workers, inputs_of,
            per_frame, store, progress, rows_made):  # threads (also while another has the pool)
        map_frames(lambda i: store(i, run_one(inputs_of(i), per_frame)), count, workers,
                   progress)
    stacked = values.arrays()
    return ProgramResult(
        values=stacked, outputs={k: stacked[k] for k in program.graph.output_ids()},
        simulations=sims.results(stacked),
        normalized=normalized[0], input_peaks=peaks.arrays())
