"""Benchmark: how long compiling and allocating takes, per target (medians; not a test).

First places the 192-virtual-antenna imaging network on the smallest multi-chip board that
holds it: the built-in boards (``compiler/hardware/boards``) are tried from the fewest cores up
(``--repetitions temporal``: the DFTs time-multiplexed), each refusal printed with its time, and
the first that fits is reported with its compile time, this process's peak resident memory and
the report's per-chip table (the issue's goal: ≤ 30 s, ≤ 2 GB).  Then prints, for the carrada
chain (`examples/chains/carrada_rd_oscfar.yaml`, calibrated on synthetic noise) and each
built-in target, the median time of every compile pass over
``--repeats`` runs, the cores used and the multiplexed stages; then the time the
192-virtual-antenna imaging network (``compiler.hardware.reference_networks``) takes to be
refused with its BudgetError.  The issue's goals: carrada + report for ``loihi`` < 1 s; the
imaging chain < 30 s and < 8 GB, or a BudgetError that says what to change.
``--only unbounded`` compiles the imaging network for ``unbounded`` alone (each population one
block), so the peak memory printed is that compile's (docs/hardware.md: well under 2 GB).

Run ``python benchmarks/allocation.py [--repeats 5] [--targets loihi loihi2]
[--only all|boards|chips|unbounded]``.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import time
from pathlib import Path

from compiler.calibration import synthetic_inputs
from compiler.compile import compile_graph
from compiler.hardware import BUILTIN_BOARDS, load_profile
from compiler.hardware.reference_networks import imaging_network
from compiler.passes import CompileContext, run_pipeline
from compiler.passes.place import Place
from compiler.passes.quantize import Quantize
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.program import CompiledProgram, Segment
from ir import Graph
from ir.errors import BudgetError

CARRADA = Path(__file__).resolve().parents[1] / "examples" / "chains" / "carrada_rd_oscfar.yaml"


def carrada(targets: list[str], repeats: int) -> None:
    graph = Graph.from_yaml(CARRADA)
    inputs = synthetic_inputs(graph, seed=0)
    for target in targets:
        runs = [compile_graph(graph, target=target, calibration_inputs=inputs)
                for _ in range(repeats)]
        names = list(runs[0].records["timings"])
        med = {n: statistics.median(r.records["timings"][n] for r in runs) for n in names}
        total = statistics.median(sum(r.records["timings"].values()) for r in runs)
        data = runs[0].records["report"].data
        multiplexed = [m["stage"] for m in runs[0].records["placement"].multiplexed]
        print(f"carrada on {target}: {total:.2f} s of compile passes (median of {repeats}); "
              f"{data['totals']['cores']} cores; multiplexed stages {multiplexed}; "
              f"frame latency fits: {data['latency']['fits']}")
        print("   " + ", ".join(f"{n} {t * 1e3:.0f} ms" for n, t in med.items()))


def imaging(targets: list[str]) -> None:
    net = imaging_network()
    for target in targets:
        start = time.perf_counter()
        prog = CompiledProgram(graph=Graph.from_yaml(CARRADA), segments=[
            Segment(kind="spiking", inputs=[], outputs=[], network=net)])
        ctx = CompileContext(target=load_profile(target))
        try:
            run_pipeline([Quantize(), Split(), Place(), ReportPass()], ctx, prog)
            outcome = "fits"
        except BudgetError as err:
            outcome = f"BudgetError: {str(err)[:160]}…"
        print(f"imaging (192 virtual rx) on {target}: {time.perf_counter() - start:.2f} s; "
              f"{outcome}")
    peak_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"peak resident memory of this process: {peak_gb:.2f} GB")


def _peak_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def boards() -> None:
    """The imaging network on the smallest built-in board that holds it, with the chip table."""
    net = imaging_network()
    graph = Graph.from_yaml(CARRADA)
    for name in sorted(BUILTIN_BOARDS, key=lambda b: load_profile(b).n_cores):
        profile = load_profile(name)
        start = time.perf_counter()
        prog = CompiledProgram(graph=graph, segments=[
            Segment(kind="spiking", inputs=[], outputs=[], network=net)])
        ctx = CompileContext(target=profile)
        try:
            run_pipeline([Quantize(), Split(repetitions="temporal"),
                          Place(repetitions="temporal"), ReportPass()], ctx, prog)
        except BudgetError as err:
            print(f"imaging (192 virtual rx) on board {name} ({profile.chips} x "
                  f"{profile.chip_profile}): {time.perf_counter() - start:.2f} s; "
                  f"BudgetError: {str(err)[:200]}…")
            continue
        seconds = time.perf_counter() - start
        data = prog.records["report"].data
        print(f"imaging (192 virtual rx) on board {name} ({profile.chips} x "
              f"{profile.chip_profile}): fits on {data['totals']['cores']:,} cores, "
              f"{data['inter_chip']['chips']} of {profile.chips} chips; compile "
              f"(quantize+split+place+report) {seconds:.2f} s; peak resident memory of this "
              f"process {_peak_gb():.2f} GB (goal ≤ 30 s, ≤ 2 GB)")
        md = prog.records["report"].to_markdown()
        print(md[md.index("## Chips"):], end="")
        return
    print("imaging (192 virtual rx): no built-in board holds it")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--targets", nargs="+", default=["loihi", "loihi2", "spinnaker2"])
    parser.add_argument("--only", choices=("all", "boards", "chips", "unbounded"),
                        default="all",
                        help="boards: only the imaging network on the boards; chips: only the "
                             "single-chip figures; unbounded: only the imaging network on "
                             "unbounded")
    args = parser.parse_args(argv)
    if args.only in ("all", "boards"):
        boards()  # first, so the peak memory printed is the imaging placement's
    if args.only in ("all", "chips"):
        carrada(args.targets, args.repeats)
        imaging(args.targets + ["unbounded"])
    if args.only == "unbounded":
        imaging(["unbounded"])


if __name__ == "__main__":
    main()
