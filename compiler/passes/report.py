"""The ``report`` pass: build the resource report of the program (``records["report"]``).

It also enforces the profile's ``max_steps_per_frame``: a stage whose steps per frame
(``time_steps``, times its repetitions where the split time-multiplexes it) exceed it is a
:class:`~ir.errors.BudgetError` naming the stage, its network, the steps and the limit.

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

from compiler.hardware import load_profile
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from compiler.report import build_report
from ir.errors import BudgetError

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
        if program.target is None and ctx.target is not None:
            program.target = ctx.target
        program.records.report = build_report(
            program, frame_rate_hz=self.frame_rate_hz, real_bits=int(self.real_bits),
            n_angle_bins=self.n_angle_bins)
        if program.target is not None:
            check_steps_per_frame(program.records.report.data["stages"],
                                  load_profile(program.target))
        return program


def check_steps_per_frame(stages: list[dict], profile) -> None:
    """Refuse a stage whose ``steps_per_frame`` exceeds ``profile.max_steps_per_frame``.

    Parameters
    ----------
    stages : list of dict
        The report's stage rows (:func:`compiler.report.stages.stage_rows`).
    profile : HardwareProfile
        The target.

    Raises
    ------
    BudgetError
        Naming the stage, its network, its steps per frame and the limit.

    Examples
    --------
    >>> row = {"node": "f", "network": "n", "steps_per_frame": 357, "time_steps": 357,
    ...        "repetitions": 1, "multiplexed": False}
    >>> check_steps_per_frame([row], load_profile("loihi"))  # no limit
    >>> tiny = load_profile("loihi").model_copy(update={"max_steps_per_frame": 100})
    >>> check_steps_per_frame([row], tiny)
    Traceback (most recent call last):
    ...
    ir.errors.BudgetError: stage 'f' of network 'n' runs 357 steps per frame (357 time \
steps), over max_steps_per_frame = 100 of loihi; use fewer time steps (option time_steps) \
or a target that runs more steps per frame
    """
    limit = profile.max_steps_per_frame
    if limit is None:
        return
    for row in stages:
        steps = row["steps_per_frame"]
        if steps <= limit:
            continue
        how = (f"{row['time_steps']} time steps x {row['repetitions']} time-multiplexed "
               "repetitions" if row["multiplexed"] else f"{row['time_steps']} time steps")
        fix = ("; use fewer time steps (option time_steps)"
               + (", repetitions='spatial'" if row["multiplexed"] else "")
               + " or a target that runs more steps per frame")
        raise BudgetError(f"stage {row['node']!r} of network {row['network']!r} runs {steps} "
                          f"steps per frame ({how}), over max_steps_per_frame = {limit} of "
                          f"{profile.name}{fix}", node=row["node"])
