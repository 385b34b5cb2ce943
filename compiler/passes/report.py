"""The ``report`` pass: build the resource report of the program (``records["report"]``).

The report's stage rows are where the profile's ``max_steps_per_frame`` is checked
(:meth:`~compiler.hardware.HardwareProfile.check_steps_per_frame`): a stage whose steps per
frame (``time_steps``, times its repetitions where the split time-multiplexes it) exceed it
is a :class:`~ir.errors.BudgetError` naming the stage, its network, the steps and the limit.

Examples
--------
>>> from pathlib import Path
>>> from compiler.passes.base import CompileContext
>>> from compiler.program import CompiledProgram
>>> from ir import Graph
>>> g = Graph.from_yaml(Path("examples/chains/carrada_rd_oscfar.yaml"))
>>> prog = ReportPass().apply(CompileContext(), CompiledProgram(graph=g))
>>> prog.records["report"].data["frame_io"][1]["bandwidth_Mbit_s"]
2.62144
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from compiler.report import build_report

__all__ = ["ReportPass"]


@dataclass(frozen=True)
class ReportPass(Pass):
    """Store :func:`compiler.report.build_report` of the program under ``records["report"]``.

    Attributes
    ----------
    frame_rate_hz : float, optional
        Frames per second (compile option ``frame_rate_hz``; None: the chain's or 10).
    real_bits : int
        Bits per real sample of frame I/O (option ``real_bits``).
    n_angle_bins : int, optional
        Angle bins of an RA map the chain does not compute (option ``n_angle_bins``);
        None: an RA map row only for a chain that computes one.
    """

    name: ClassVar[str] = "report"
    frame_rate_hz: float | None = None
    real_bits: int = 16
    n_angle_bins: int | None = None

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        if program.target is None:
            program.target = ctx.target
        program.records.report = build_report(
            program, frame_rate_hz=self.frame_rate_hz, real_bits=int(self.real_bits),
            n_angle_bins=self.n_angle_bins)
        program.target.check_steps_per_frame(program.records.report.data["stages"])
        return program
