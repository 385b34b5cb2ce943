"""``radarsnn bench``: frames per second of the spiking chain vs the conventional numpy chain.

For a preset's range-Doppler-CFAR chain (carrada: 8 virtual rx × 64 chirps ×
256 samples → range S-FT → Doppler S-FT → |.|² → Σrx → OS-CFAR) the bench
times, in one run and on the same frame: the conventional chain
(:func:`ir.evaluate`), the compiled chain on the reference simulator in closed
form and in step mode (plans built once, as a long run would), and optionally
Brian2 on the range S-FT stage.  Each figure is the median of ``repeats`` runs;
BLAS is limited to ``threads`` threads (1 by default: "one core").  Ratios are
computed from figures of the same run, never across runs.

Examples
--------
>>> median_s(lambda: None, repeats=3) >= 0.0
True
"""

from __future__ import annotations

import platform
import resource
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

__all__ = ["BenchReport", "median_s", "run_bench"]


def median_s(fn: Callable[[], object], repeats: int = 5) -> float:
    """The median wall time of ``repeats`` calls of ``fn`` (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _peak_rss_gb() -> float:
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kB on Linux
    return kb / 1e6 if sys.platform != "darwin" else kb / 1e9


@dataclass
class BenchReport:
    """Median seconds per frame and the ratios the issue's goals are stated in."""

    preset: str
    repeats: int
    threads: int
    machine: str
    seconds: dict[str, float] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    peak_rss_gb: float = 0.0

    @property
    def frames_per_s(self) -> dict[str, float]:
        """Frames per second of every timed engine."""
        return {k: 1.0 / v for k, v in self.seconds.items() if v > 0}

    def ratios(self) -> dict[str, float]:
        """``closed / conventional``, ``step / conventional`` and ``brian2 / closed-stage``."""
        s, out = self.seconds, {}
        for mode in ("closed", "step"):
            if mode in s and "conventional" in s:
                out[f"{mode}_over_conventional"] = s[mode] / s["conventional"]
        for mode in ("closed", "step"):
            if "brian2_range_stage" in s and f"{mode}_range_stage" in s:
                out[f"brian2_over_{mode}_range_stage"] = (s["brian2_range_stage"]
                                                          / s[f"{mode}_range_stage"])
        return out

    def to_text(self) -> str:
        """The figures as a table, with the goals."""
        lines = [f"radarsnn bench: {self.preset} chain, median of {self.repeats}, "
                 f"{self.threads} BLAS thread(s), {self.machine}",
                 f"  {'engine':<22} {'s/frame':>10} {'frames/s':>10}"]
        for k, v in self.seconds.items():
            lines.append(f"  {k:<22} {v:>10.4f} {1.0 / v if v else float('inf'):>10.2f}")
        goals = {"closed_over_conventional": "goal <= 20",
                 "brian2_over_closed_range_stage": "goal >= 100",
                 "brian2_over_step_range_stage": "goal >= 10"}
        for k, v in self.ratios().items():
            lines.append(f"  {k:<32} {v:>8.1f}  {goals.get(k, '')}")
        if "closed" in self.seconds:
            lines.append(f"  closed form: {1.0 / self.seconds['closed']:.1f} frames/s "
                         "(goal >= 10 on one core)")
        lines.append(f"  peak RSS of the radarsnn runs {self.peak_rss_gb:.2f} GB (goal <= 2 GB; "
                     "measured before Brian2 runs)")
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able figures, ratios and frames/s."""
        return {**asdict(self), "ratios": self.ratios(), "frames_per_s": self.frames_per_s}


def _range_stage(config, frame_adc, calibration_adc, repeats: int, report: BenchReport) -> None:
    """Closed form vs Brian2 on the range S-FT of one receiver (Brian2 is an optional extra)."""
    from backends.brian2 import import_brian2, simulate_brian2
    from backends.reference import build_plan, simulate
    from ir.errors import RadarSNNError

    try:
        import_brian2()
    except (ImportError, RadarSNNError) as err:
        report.notes.append(f"Brian2 not timed ({err}); install the extra: pip install -e "
                            "'.[brian2]'")
        return
    from compiler.chains import range_chain
    from compiler.compile import compile_graph

    graph = range_chain(config, rx=1)
    program = compile_graph(graph, None, calibration_inputs={"adc": calibration_adc[:1]})
    (net,) = program.networks
    inputs = {net.encoders[0].port: frame_adc[:1]}
    plan = build_plan(net, "float64")
    report.seconds["closed_range_stage"] = median_s(
        lambda: simulate(net, inputs, mode="closed", plan=plan, out_of_range="clip"), repeats)
    report.seconds["step_range_stage"] = median_s(
        lambda: simulate(net, inputs, mode="step", plan=plan, out_of_range="clip"),
        max(1, min(repeats, 3)))
    report.seconds["brian2_range_stage"] = median_s(
        lambda: simulate_brian2(net, inputs, out_of_range="clip"), max(1, min(repeats, 5)))
    same = simulate_brian2(net, inputs, out_of_range="clip").spike_counts == simulate(
        net, inputs, mode="step", out_of_range="clip").spike_counts
    report.notes.append(f"range stage: 1 rx x {config.n_chirps} chirps x {config.n_samples} "
                        f"samples, {net.n_steps} steps; Brian2 (numpy target) spike counts "
                        f"{'equal' if same else 'DIFFER from'} the step engine's")


def run_bench(preset_name: str = "carrada", *, repeats: int = 5, step_repeats: int | None = None,
              threads: int = 1, modes: tuple[str, ...] = ("closed", "step"),
              brian2: bool = True, progress=None) -> BenchReport:
    """Time the conventional and the spiking chain of ``preset_name`` (see module docstring).

    Parameters
    ----------
    preset_name : str
        Radar preset with a scene.
    repeats : int
        Timed runs per figure (median); step mode uses ``step_repeats`` (default ``repeats``).
    threads : int
        BLAS threads while timing (threadpoolctl).
    modes : tuple of str
        Simulator engines to time.
    brian2 : bool
        Also time Brian2 on the range S-FT stage when it is installed.
    progress : callable, optional
        ``progress(stage, message)``.
    """
    from threadpoolctl import threadpool_limits

    from backends.reference import program_plans, run_program
    from compiler.chains import range_doppler_chain
    from compiler.compile import compile_graph
    from ir import evaluate
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame

    say = progress or (lambda _s, _m: None)
    config = preset(preset_name)
    scene = SCENE_PRESETS[preset_name]()
    frame = simulate_frame(config, scene, seed=0).adc
    calibration = simulate_frame(config, scene, seed=1).adc
    graph = range_doppler_chain(config)
    report = BenchReport(preset=preset_name, repeats=repeats, threads=threads,
                         machine=f"{platform.machine()} {platform.processor() or ''} "
                                 f"Python {platform.python_version()}".replace("  ", " "))
    program = compile_graph(graph, None, calibration_inputs={"adc": calibration})
    say("bench", "compiled")
    plans = program_plans(program)
    with threadpool_limits(limits=threads):
        report.seconds["conventional"] = median_s(lambda: evaluate(graph, {"adc": frame}),
                                                  repeats)
        say("bench", "conventional done")
        for mode in modes:
            n = repeats if mode != "step" else (step_repeats or repeats)
            report.seconds[mode] = median_s(
                lambda m=mode: run_program(program, {"adc": frame}, mode=m, plans=plans,
                                           out_of_range="clip"), n)
            say("bench", f"{mode} done")
        report.peak_rss_gb = _peak_rss_gb()
        if brian2:
            _range_stage(config, frame, calibration, repeats, report)
    report.notes.append("simulator figures exclude compilation and plan building (done once)")
    return report
