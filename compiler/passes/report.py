"""The ``report`` pass: build the resource report of the program (``records["report"]``).

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

    Options read from ``ctx.options``: ``frame_rate_hz``, ``real_bits`` (16), ``n_angle_bins``
    (256).
    """

    name: ClassVar[str] = "report"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        opts = ctx.options
        if program.target is None and ctx.target is not None:
            program.target = ctx.target
        program.records[self.name] = build_report(
            program, frame_rate_hz=opts.get("frame_rate_hz"),
            real_bits=int(opts.get("real_bits", 16)),
            n_angle_bins=opts.get("n_angle_bins", 256))
        return program
