"""``compile_graph``: a radar chain in, a :class:`~compiler.program.CompiledProgram` out.

The pipeline is a list of passes (see :mod:`compiler.passes`) run in order on
an explicit :class:`~compiler.passes.CompileContext`:

``verify`` → ``fuse-linear`` (windows folded into DFT weights) → ``calibrate``
(value ranges → encoder ranges and thresholds) → ``lower`` (each node into
its chosen motif or a host segment) and, for a hardware target, ``quantize``
→ ``split`` → ``place`` → ``report``.

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 4}},
...     {"id": "o", "op": "output", "input": "a"}]})
>>> program = compile_graph(g)                 # for loihi2, the default target
>>> [s.kind for s in program.segments], list(program.records["timings"])[:4]
(['host'], ['verify', 'fuse-linear', 'static-split', 'calibrate'])
>>> sorted(compile_graph(g, target=None).records["timings"])  # no allocation passes
['calibrate', 'fuse-linear', 'lower', 'static-split', 'verify']
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from compiler.accuracy.check import check_program
from compiler.accuracy.contract import Tolerances, split_folds
from compiler.accuracy.select import ops_to_search, search
from compiler.accuracy.simulator import Simulator
from compiler.compile_guards import check_compile, limits_from_options
from compiler.hardware import NO_TARGET, HardwareProfile, load_profile
from compiler.lowering import LoweringRegistry, default_registry
from compiler.memo import CompileMemo
from compiler.option_checks import check_options
from compiler.passes import CompileContext, run_pipeline
from compiler.passes.base import Progress
from compiler.pipeline import (
    EXTRA_OPTIONS,
    calibrate_pass,
    default_pipeline,
    lower_pass,
    motif_settings,
)
from compiler.program import CompiledProgram
from compiler.report import add_measured_activity
from ir import Graph
from ir.errors import CompileError, IRError
from ir.frames import n_frames
from ir.interpreter import EvalRegistry, eval_registry
from ir.model import short_repr

__all__ = ["EXTRA_OPTIONS", "TargetSpec", "calibrate_pass", "compile_graph", "default_pipeline",
           "lower_pass", "motif_settings"]

#: What ``compile_graph``'s ``target`` takes: a built-in name, a YAML path, a profile, or
#: None (no target: no allocation passes; the lowering reads
#: :data:`~compiler.hardware.NO_TARGET`).
TargetSpec = str | Path | HardwareProfile | None


def compile_graph(graph: Graph | str | Path, target: TargetSpec = "loihi2", *,
                  motifs: Mapping[str, str] | None = None, calibration: str = "static",
                  calibration_inputs: Mapping[str, np.ndarray] | None = None,
                  time_steps: int | None = None, weight_bits: int | None = None,
                  registry: LoweringRegistry | None = None,
                  evaluators: EvalRegistry | None = None,
                  progress: Progress | None = None,
                  options: Mapping[str, Any] | None = None,
                  simulator: Simulator | None = None,
                  check_inputs: Mapping[str, np.ndarray] | None = None,
                  accuracy: str = "error",
                  tolerances: Tolerances | None = None) -> CompiledProgram:
    """Compile a radar chain into spiking and host segments.

    Parameters
    ----------
    graph : Graph or path
        The chain (a path is read with :meth:`ir.Graph.from_yaml`).
    target : str, Path, HardwareProfile or None, default "loihi2"
        A built-in profile name (``loihi``, ``loihi2``, ``spinnaker2``,
        ``unbounded``), a YAML profile path, a profile object, or None (no
        allocation passes: the spiking network and host segments only, for
        accuracy studies where the chip does not matter; the lowering reads
        :data:`~compiler.hardware.NO_TARGET`). Loaded once, here: every pass and
        lowering rule reads the same :class:`~compiler.hardware.HardwareProfile`
        (``ctx.target``), and so does every compile of a measured search.
    motifs : mapping, optional
        Motif per node id or op name (e.g. ``{"dft": "time", "mag": "host"}``).
    calibration : {"static", "per-input"}
        The calibration policy.
    calibration_inputs : mapping, optional
        Sample arrays by input node id for calibration.
    time_steps : int, optional
        Override of the per-motif time window.
    weight_bits : int, optional
        Quantize weights to this many bits (None: exact floats).
    registry : LoweringRegistry, optional
        Lowering rules (default :func:`compiler.lowering.default_registry`).
    evaluators : mapping of op class to implementation, optional
        Reference implementations of new ops (``impl(node_id, op, args, types) ->
        array``), added to :data:`ir.interpreter.EVAL_REGISTRY`: calibration evaluates
        with them, and the program keeps them (``program.evaluators``) for its
        host segments, so :func:`backends.reference.run_program` runs it as is.
        Nothing global changes (docs/howto-op.md).
    progress : callable, optional
        ``progress(pass_name, message)`` on long work.
    options : mapping, optional
        Motif-specific options, see :data:`EXTRA_OPTIONS`.
    simulator : Simulator, optional
        Measure the accuracy contract (:mod:`compiler.accuracy`) with this simulator
        and choose the motifs the user did not pin (``motifs="auto"``,
        :mod:`compiler.accuracy.select`): the cheapest spiking configuration whose every
        stage keeps the contract on held-back frames and whose steps fit the frame
        period. :func:`radarsnn.compile_graph <radarsnn>` and ``radarsnn compile`` pass
        the reference simulator; without one nothing is measured
        (``program.records.accuracy`` is None).
    check_inputs : mapping, optional
        Frames to check on (default: the last third of the calibration frames, held
        back from the calibration; with one calibration frame the check runs on it and
        says it is not held out).
    accuracy : {"error", "warn", "off"}
        With a simulator, when no configuration keeps the contract: raise
        :class:`~ir.errors.AccuracyError` naming the stage (``error``), or keep the
        best configuration and say so in the records (``warn``); ``off`` measures nothing.
    tolerances : Tolerances, optional
        The contract (:class:`compiler.accuracy.contract.Tolerances`).

    Returns
    -------
    CompiledProgram

    Raises
    ------
    IRError
        The graph does not verify (naming the node).
    CompileError
        An option or motif cannot be honoured (naming the node and the fix), an
        option's value breaks its rule (:mod:`compiler.option_checks`), ``evaluators``
        is malformed, or a node left on the host has no implementation (naming it).
    BudgetError
        The program does not fit the target (naming the node, budget and amount), or
        its estimated compile memory or time exceeds the options ``max_memory_bytes``
        / ``max_time_s`` (:mod:`compiler.compile_guards`; checked before anything is built).
    """
    if isinstance(graph, (str, Path)):
        graph = Graph.from_yaml(Path(graph))
    if accuracy not in ("error", "warn", "off"):
        raise CompileError(f"accuracy={short_repr(accuracy)} must be error, warn or off")
    if target is not None:  # loaded once: every compile of a search reads the same profile
        target = load_profile(target)
    once = dict(target=target, calibration=calibration, registry=registry,
                evaluators=evaluators, progress=progress)
    if simulator is None or accuracy == "off":
        return _compile_once(graph, motifs=motifs, calibration_inputs=calibration_inputs,
                             time_steps=time_steps, weight_bits=weight_bits, options=options,
                             **once)
    if not isinstance(simulator, Simulator):
        raise CompileError(f"simulator={short_repr(simulator)} has no run(program, inputs) "
                           "method (compiler.accuracy.simulator.Simulator)")
    if not isinstance(graph, Graph):
        raise CompileError(f"compile_graph takes a Graph or a chain file path; got "
                           f"{type(graph).__name__}")
    return _compile_checked(graph, motifs=dict(motifs or {}),
                            calibration_inputs=dict(calibration_inputs or {}),
                            check_inputs=check_inputs, time_steps=time_steps,
                            weight_bits=weight_bits, options=dict(options or {}),
                            simulator=simulator, accuracy=accuracy, tolerances=tolerances,
                            once=once)


def _compile_checked(graph: Graph, *, motifs: dict, calibration_inputs: dict, check_inputs,
                     time_steps, weight_bits, options: dict, simulator: Simulator,
                     accuracy: str, tolerances: Tolerances | None,
                     once: dict) -> CompiledProgram:
    """The measured compile: folds, the ladder search, the contract kept in the records."""
    frames = n_frames(graph.infer_types(), calibration_inputs, f"chain {graph.name!r}") \
        if calibration_inputs else None
    if check_inputs is not None:
        fit, check, held_out, note = calibration_inputs, dict(check_inputs), True, ""
    else:
        fit, check = split_folds(calibration_inputs, frames)
        held_out, note = check is not None, ""
        if check is None:
            check = calibration_inputs
            note = ("one calibration frame: checked on it (pass more frames or "
                    "check_inputs to hold some back)")
    if not check:
        program = _compile_once(graph, motifs=motifs, time_steps=time_steps,
                                weight_bits=weight_bits, options=options, **once)
        if not any(seg.kind == "spiking" for seg in program.segments):
            return program  # nothing spiking: nothing to measure
        raise CompileError("the accuracy check needs frames: pass calibration_inputs or "
                           "check_inputs (or accuracy='off' to compile unmeasured)")

    calibrations: list = []  # CompileContext.calibrations: the attempts' frames measured once
    memo = CompileMemo()  # CompileContext.memo: the attempts' other shared work, done once

    def build(auto_motifs: dict[str, str], auto_options: dict[str, Any]) -> CompiledProgram:
        # the user's motifs and options win over the rungs'
        return _compile_once(graph, motifs={**auto_motifs, **motifs}, calibration_inputs=fit,
                             time_steps=time_steps, weight_bits=weight_bits, **once,
                             options={**auto_options, **options}, calibrations=calibrations,
                             memo=memo)

    runs: list[tuple[CompiledProgram, Any]] = []  # each program measured, with its run

    def measure(program: CompiledProgram):
        run = simulator.run(program, check)
        runs.append((program, run))
        return check_program(program, check, simulator, tolerances=tolerances,
                             held_out=held_out, note=note, run=run)

    program, selection = search(ops_to_search(graph, motifs), build, measure,
                                accuracy=accuracy)
    chosen = selection.attempts[selection.chosen]
    program.records.accuracy = chosen.contract
    program.records.extra["motif_selection"] = selection.to_dict()
    run = next((r for p, r in runs if p is program), None)
    if program.records.report is not None and getattr(run, "simulations", ()):
        # the energy per frame on the spikes counted on the held-back frames
        add_measured_activity(program.records.report, program, run.simulations)
    if program.records.report is not None:  # shown per stage in the report
        program.records.report.data["accuracy"] = chosen.contract.to_dict()
        program.records.report.data["motif_selection"] = selection.to_dict()
    return program


def _compile_once(graph: Graph | str | Path, target: HardwareProfile | None, *,
                  motifs: Mapping[str, str] | None = None, calibration: str = "static",
                  calibration_inputs: Mapping[str, np.ndarray] | None = None,
                  time_steps: int | None = None, weight_bits: int | None = None,
                  registry: LoweringRegistry | None = None,
                  evaluators: EvalRegistry | None = None,
                  progress: Progress | None = None,
                  options: Mapping[str, Any] | None = None,
                  calibrations: list | None = None,
                  memo: CompileMemo | None = None) -> CompiledProgram:
    """One compile with the motifs given (compile_graph without a simulator)."""
    unknown = sorted(set(options or {}) - set(EXTRA_OPTIONS))
    if unknown:
        raise CompileError(f"unknown compile options {unknown}; known: {sorted(EXTRA_OPTIONS)}")
    options = check_options(options, time_steps=time_steps, weight_bits=weight_bits,
                            calibration=calibration, motifs=motifs)
    max_memory_bytes, max_time_s = limits_from_options(options)
    if not isinstance(graph, Graph):
        raise CompileError(f"compile_graph takes a Graph or a chain file path; got "
                           f"{type(graph).__name__}")
    check_compile(graph, max_memory_bytes=max_memory_bytes, max_time_s=max_time_s)
    try:
        impls = eval_registry(evaluators)
    except IRError as err:
        raise CompileError(f"compile_graph: {err}") from None
    profile = NO_TARGET if target is None else target  # typed, the same for every pass
    options = {**dict(options or {}), "motifs": dict(motifs or {}), "calibration": calibration,
               "time_steps": time_steps, "weight_bits": weight_bits}
    ctx = CompileContext(target=profile,
                         calibration_inputs=dict(calibration_inputs or {}),
                         lowering=registry or default_registry(),
                         evaluators=dict(evaluators or {}), calibrations=calibrations,
                         memo=memo)
    if progress is not None:
        if not callable(progress):
            raise CompileError(f"compile_graph: progress={progress!r:.60} is not callable; give "
                               "a function progress(pass_name, message) or None")
        ctx.progress = progress
    program = CompiledProgram(graph=graph, options=options, target=target,
                              calibration_policy=calibration)
    program = run_pipeline(default_pipeline(options, hardware=target is not None), ctx, program)
    _check_host_implementations(program, impls)
    return program


def _check_host_implementations(program: CompiledProgram, impls: Mapping[type, Any]) -> None:
    """Refuse a host segment whose op has no reference implementation (it could not run)."""
    for node in program.host_nodes:
        op = program.graph.op(node)
        if type(op) not in impls and not type(op).has_evaluate():
            name = type(op).__name__
            raise CompileError(
                f"node {node!r} ({op.op}) runs on the host, but {name} has no reference "
                f"implementation to run it there; define {name}.evaluate, pass compile_graph(..., "
                f"evaluators={{{name}: function}}) or register a spiking motif for it "
                "(docs/howto-op.md)", node=node)
