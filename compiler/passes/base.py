"""The pass contract: a named, frozen unit that turns a valid program into a valid program.

Imitating xDSL, a pass is a frozen dataclass with a class-level ``name`` (the
kebab-case name used in options and reports), its options as fields, and one
``apply(ctx, program)``.  The contract: given a program whose graph verifies,
return one whose graph still verifies and whose segments are consistent.
Passes never read globals; everything they need is in the explicit
:class:`CompileContext` or in their own typed fields — the options of a pass are its
fields, set from the compile options in one place (:func:`compiler.compile.default_pipeline`).

Examples
--------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Count(Pass):
...     name = "count"
...     def apply(self, ctx, program):
...         program.records[self.name] = len(program.graph.topological_order())
...         return program
>>> from ir import Graph
>>> from compiler.program import CompiledProgram
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 4}},
...     {"id": "o", "op": "output", "input": "a"}]})
>>> records = run_pipeline([Count()], CompileContext(), CompiledProgram(graph=g)).records
>>> records["count"], sorted(records["timings"])
(2, ['count'])
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from compiler.hardware import NO_TARGET, HardwareProfile, load_profile
from compiler.memo import CompileMemo
from compiler.program import CompiledProgram
from ir.errors import CompileError

__all__ = ["Pass", "CompileContext", "run_pipeline", "Progress"]

log = logging.getLogger(__name__)

#: ``progress(pass_name, message)``: called by passes on long work.
Progress = Callable[[str, str], None]


def _silent(_name: str, _message: str) -> None:
    return None


@dataclass
class CompileContext:
    """Everything a pass may consult besides the program itself.

    Parameters
    ----------
    target : HardwareProfile
        The hardware profile every pass and lowering rule reads
        (:class:`~compiler.hardware.HardwareProfile`); :data:`~compiler.hardware.NO_TARGET`
        (the default) for a compile without one.  A built-in name or a YAML path is
        loaded here, once.
    calibration_inputs : dict of str to ndarray
        Sample inputs by input node id, for the calibrate pass.
    lowering : object, optional
        The lowering registry (``compiler.lowering.LoweringRegistry``) to use.
    evaluators : mapping of op class to implementation
        Reference implementations added to :data:`ir.interpreter.EVAL_REGISTRY` (new ops,
        ``impl(node_id, op, args, types) -> array``): what ``calibrate`` evaluates with
        and what the program's host segments run (:func:`run_pipeline` records them).
    progress : callable
        ``progress(pass_name, message)`` for long work (silent by default).
    calibrations : list, optional
        Calibrations measured on these ``calibration_inputs`` by earlier compiles of the
        same chain, for the calibrate pass to reuse (a measured compile's attempts share
        one list: :func:`compiler.passes.calibrate.Calibrate`); None: measure every time.
    memo : CompileMemo, optional
        Work shared by the attempts of one measured compile (:mod:`compiler.memo`: the
        DFT weights' rounding, equal networks, their splits); None: everything is computed.
    """

    target: HardwareProfile = NO_TARGET
    calibration_inputs: Mapping[str, Any] = field(default_factory=dict)
    lowering: Any = None
    evaluators: Mapping[type, Callable[..., Any]] = field(default_factory=dict)
    progress: Progress = _silent
    calibrations: list | None = None
    memo: CompileMemo | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.target, HardwareProfile):
            if self.target is None:  # the old "no target": say what to give instead
                raise CompileError("CompileContext(target=None): give a HardwareProfile, a "
                                   "profile name or path, or compiler.hardware.NO_TARGET for "
                                   "a compile without a target")
            self.target = load_profile(self.target)


@dataclass(frozen=True)
class Pass:
    """Base class of compiler passes: subclass, set ``name``, implement :meth:`apply`."""

    name: ClassVar[str] = "pass"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        """Transform ``program``; valid program in, valid program out."""
        raise NotImplementedError(f"pass {self.name!r} does not implement apply()")


def run_pipeline(passes: Iterable[Pass], ctx: CompileContext,
                 program: CompiledProgram) -> CompiledProgram:
    """Apply ``passes`` in order, timing each (seconds stored in ``records["timings"]``).

    The context's extra evaluators, if any, are kept as ``program.evaluators``
    (op class → implementation): the program's host segments run with them
    (:func:`backends.reference.run_program`), so a program compiled with a new op
    runs as compiled.  They stay in memory: a saved program artifact holds data only.
    """
    if ctx.evaluators:
        program.evaluators = dict(ctx.evaluators)
    timings = program.records.timings
    for p in passes:
        ctx.progress(p.name, "start")
        start = time.perf_counter()
        program = p.apply(ctx, program)
        timings[p.name] = time.perf_counter() - start
        log.info("pass %s: %.3f s", p.name, timings[p.name])
        ctx.progress(p.name, "done")
    return program
