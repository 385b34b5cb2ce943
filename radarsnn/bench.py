"""``radarsnn bench``: frames per second of the spiking chain vs the conventional numpy chain.

For a preset's range-Doppler-CFAR chain (carrada: 8 virtual rx × 64 chirps ×
256 samples → range S-FT → Doppler S-FT → |.|² → Σrx → OS-CFAR) the bench
times, in one run and on the same frame: the conventional chain
(:func:`ir.evaluate`), the compiled chain on the reference simulator in closed
form and in step mode (plans built once, as a long run would), and optionally
Brian2 on the range S-FT stage.  Each figure is the median of ``repeats`` runs;
BLAS is limited to ``threads`` threads (1 by default: "one core").  Ratios are
computed from figures of the same run, never across runs.  Brian2 runs last: it builds a few
GB of synapses per call, and the memory it frees keeps the kernel busy for a while after it
(on a virtual machine that hands freed pages back to its host), which would slow whatever
was timed next.

The *floor* (:mod:`backends.reference.floor`) is the dense matrix products the
closed form must apply — the same shared matrices, as plain numpy products —
timed in the same run, each of its runs in turn with one of the closed form's (a
drift of the host's speed moves both alike): ``closed_over_floor`` says what the rest
of the closed form (encoding, the analytic crossings, the CFAR, decoding) costs on top.  The
load average (1, 5, 15 min) is read before and after the timings.

``motif="resonator"`` (``radarsnn bench --motif resonator``) times the chain with
``resonator`` range and Doppler DFTs instead (:data:`MOTIF_CHAINS`: compiled for
``loihi2``, the chip's 12-bit fixed-point rotations, as the compiler's accuracy search picks
them on hard scenes); its floor is the rotations every resonator must do per input step
(:func:`backends.reference.floor.rotation_floors`).

Examples
--------
>>> median_s(lambda: None, repeats=3) >= 0.0
True
"""

from __future__ import annotations

import os
import platform
import resource
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

__all__ = ["BenchReport", "MOTIF_CHAINS", "chain_inputs", "interleaved_medians", "median_s",
           "run_bench"]

#: ``--motif`` → (target, motifs) of the chain ``radarsnn bench`` builds instead of the
#: default (unbounded target, default motifs).
MOTIF_CHAINS: dict[str, tuple[str, dict[str, str]]] = {
    "resonator": ("loihi2", {"dft": "resonator"}),
}


def median_s(fn: Callable[[], object], repeats: int = 5) -> float:
    """The median wall time of ``repeats`` calls of ``fn`` (after one warm-up call)."""
    return interleaved_medians({"fn": fn}, repeats)["fn"]


def interleaved_medians(fns: dict[str, Callable[[], object]], repeats: int = 5) -> dict[str, float]:
    """Median wall time of each of ``fns``, their calls taken in turn (after one warm-up each).

    Timing ``a`` seven times and then ``b`` seven times lets a drift of the host's
    speed (another tenant, a frequency step) between the two series bias ``a / b``;
    taken in turn, both series see the same host.

    Examples
    --------
    >>> sorted(interleaved_medians({"a": lambda: None, "b": lambda: None}, repeats=3))
    ['a', 'b']
    """
    for fn in fns.values():
        fn()
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(ts) for name, ts in times.items()}


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
    #: The user's path (:mod:`radarsnn.bench_user`): seconds of ``run_program`` as called
    #: (per frame) and of ``compile_graph`` with and without the accuracy check.
    user_path: dict[str, float] = field(default_factory=dict)
    #: Threads of the frames-axis figure (the available cores) and frames on its axis.
    workers: int = 0
    n_frames_axis: int = 0
    #: What those workers were: the default of ``RunOptions.parallel`` as it ran here
    #: (``"threads"``, or ``"processes"`` where the system can fork).
    parallel: str = ""
    #: Whether the process held freed memory for reuse while timing
    #: (:func:`backends.reference.heap.hold_freed_memory`: the ``radarsnn`` command does).
    freed_memory_held: bool = False
    #: ``user_s`` / ``system_s``: CPU seconds of the frames-axis timings (getrusage).
    cpu: dict[str, float] = field(default_factory=dict)
    #: ``{phase: {"user_s", "system_s"}}``: the CPU of each stage of the bench, and
    #: ``process``: of the whole process when it ended (imports included).
    cpu_phases: dict[str, dict[str, float]] = field(default_factory=dict)
    #: The chain timed (a preset's range-Doppler chain, or a chain file).
    chain: str = ""
    #: ``os.getloadavg()`` (1, 5, 15 min) before and after the timings.
    load_before: tuple[float, float, float] = (0.0, 0.0, 0.0)
    load_after: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: The floor's products: ``"id (rows x n_in x n_out)"``.
    floor_products: list[str] = field(default_factory=list)
    #: The DFT motif of the chain (``MOTIF_CHAINS``), "" for the default chain.
    motif: str = ""

    @property
    def frames_per_s(self) -> dict[str, float]:
        """Frames per second of every timed engine."""
        return {k: 1.0 / v for k, v in self.seconds.items() if v > 0}

    def ratios(self) -> dict[str, float]:
        """``closed / conventional``, ``step / conventional``, ``closed / floor`` (and
        ``/ floor_core``) and ``brian2 / {closed,step}_range_stage``."""
        s, out = self.seconds, {}
        for mode in ("closed", "step"):
            if mode in s and "conventional" in s:
                out[f"{mode}_over_conventional"] = s[mode] / s["conventional"]
        for floor in ("floor", "floor_core"):
            if "closed" in s and s.get(floor):
                out[f"closed_over_{floor}"] = s["closed"] / s[floor]
        for mode in ("closed", "step"):
            if "brian2_range_stage" in s and f"{mode}_range_stage" in s:
                out[f"brian2_over_{mode}_range_stage"] = (s["brian2_range_stage"]
                                                          / s[f"{mode}_range_stage"])
        return out

    def to_text(self) -> str:
        """The figures as a table, with the goals."""
        load = "load average {:.2f} {:.2f} {:.2f}".format
        lines = [f"radarsnn bench: {self.chain or self.preset} chain, median of {self.repeats}, "
                 f"{self.threads} BLAS thread(s), {self.machine}",
                 f"  {load(*self.load_before)} before, {load(*self.load_after)} after "
                 f"({os.cpu_count()} cores)",
                 f"  {'engine':<22} {'s/frame':>10} {'frames/s':>10}"]
        for k, v in self.seconds.items():
            lines.append(f"  {k:<22} {v:>10.4f} {1.0 / v if v else float('inf'):>10.2f}")
        if self.floor_products:
            lines.append("  floor: plain numpy products " + ", ".join(self.floor_products))
        goals = {"closed_over_conventional": "goal <= 20", "closed_over_floor": "goal <= 2",
                 "brian2_over_closed_range_stage": "goal >= 100",
                 "brian2_over_step_range_stage": "goal >= 100"}
        for k, v in self.ratios().items():
            lines.append(f"  {k:<32} {v:>8.2f}  {goals.get(k, '')}")
        if "closed" in self.seconds:
            lines.append(f"  closed form: {1.0 / self.seconds['closed']:.1f} frames/s "
                         "(goal >= 10 on one core)")
        lines.append(f"  peak RSS of the radarsnn runs {self.peak_rss_gb:.2f} GB (goal <= 2 GB; "
                     "measured before Brian2 runs)")
        from radarsnn.bench_user import phase_lines, user_path_lines

        lines += user_path_lines(self)
        lines += phase_lines(self.cpu_phases)
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able figures, ratios and frames/s (``user_path_ratios``: the user's path's)."""
        from radarsnn.bench_user import phase_ratios, user_path_ratios

        return {**asdict(self), "ratios": self.ratios(), "frames_per_s": self.frames_per_s,
                "cpu_count": os.cpu_count(),
                "user_path_ratios": user_path_ratios(self.user_path, self.cpu),
                "system_over_user_by_phase": phase_ratios(self.cpu_phases)}


def _range_stage(config, frame_adc, calibration_adc, repeats: int, report: BenchReport) -> None:
    """Closed form vs Brian2 on the range S-FT of one receiver (Brian2 is an optional extra)."""
    from backends.brian2 import import_brian2, simulate_brian2
    from backends.reference import build_plan, simulate
    from ir.errors import RadarSNNError

    try:
        import_brian2()
    except (ImportError, RadarSNNError) as err:
        report.notes.append(f"Brian2 cannot be imported here, not timed ({err}); install the "
                            "extra (pip install -e '.[brian2]'), or measure it with "
                            "benchmarks/simulator.py in its own venv (benchmarks/README.md)")
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
    last: dict[str, object] = {}  # the last timed result of each: compared, not rerun

    def kept(name: str, run: Callable[[], object]) -> Callable[[], object]:
        return lambda: last.__setitem__(name, run())

    report.seconds.update(interleaved_medians({  # in turn: one host drift for both
        "step_range_stage": kept("step", lambda: simulate(net, inputs, mode="step", plan=plan,
                                                          out_of_range="clip")),
        "brian2_range_stage": kept("brian2", lambda: simulate_brian2(net, inputs,
                                                                     out_of_range="clip"))},
        max(1, min(repeats, 3))))
    same = last["brian2"].spike_counts == last["step"].spike_counts
    report.notes.append(f"range stage: 1 rx x {config.n_chirps} chirps x {config.n_samples} "
                        f"samples, {net.n_steps} steps; Brian2 (numpy target) spike counts "
                        f"{'equal' if same else 'DIFFER from'} the step engine's")


def run_bench(preset_name: str = "carrada", *, repeats: int = 5, step_repeats: int | None = None,
              user_path: bool = True,
              threads: int = 1, modes: tuple[str, ...] = ("closed", "step"),
              brian2: bool = True, progress=None, chain=None,
              motif: str | None = None) -> BenchReport:
    """Time the conventional and the spiking chain of ``preset_name`` (see module docstring).

    Parameters
    ----------
    preset_name : str
        Radar preset with a scene.
    repeats : int
        Timed runs per figure (median); step mode uses ``step_repeats`` (default ``repeats``).
    user_path : bool
        Also time the user's path (:mod:`radarsnn.bench_user`): ``run_program`` as called
        on one frame and on a frames axis (1 and N workers), and ``compile_graph`` with
        and without the accuracy check.
    threads : int
        BLAS threads while timing (threadpoolctl).
    modes : tuple of str
        Simulator engines to time.
    brian2 : bool
        Also time Brian2 on the range S-FT stage when it is installed.
    progress : callable, optional
        ``progress(stage, message)``.
    chain : path, optional
        A chain file (YAML) to time instead of the preset's range-Doppler chain; its
        ``adc`` input is cut from the preset's frames (:func:`chain_inputs`).
    motif : str, optional
        A key of :data:`MOTIF_CHAINS`: compile the chain with that DFT motif and target
        (Brian2 is then not timed: its range stage is the default chain's).

    Raises
    ------
    RadarConfigError
        If ``chain``'s ``adc`` input does not fit inside the preset's frame.
    """
    from threadpoolctl import threadpool_limits

    from backends.reference import program_plans, run_program
    from backends.reference.floor import floor_calls, floor_products, rotation_floors
    from compiler.chains import range_doppler_chain
    from compiler.compile import compile_graph
    from ir import Graph, evaluate
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame
    from radarsnn.bench_user import cpu_phase, process_cpu

    say = progress or (lambda _s, _m: None)
    config = preset(preset_name)
    scene = SCENE_PRESETS[preset_name]()
    frame = simulate_frame(config, scene, seed=0).adc
    calibration = simulate_frame(config, scene, seed=1).adc
    graph = range_doppler_chain(config) if chain is None else Graph.from_yaml(chain)
    frame, calibration = chain_inputs(graph, frame), chain_inputs(graph, calibration)
    report = BenchReport(preset=preset_name, repeats=repeats, threads=threads,
                         machine=f"{platform.machine()} {platform.processor() or ''} "
                                 f"Python {platform.python_version()}".replace("  ", " "),
                         chain=graph.name if chain is not None else "", load_before=os.getloadavg())
    phases = report.cpu_phases
    with cpu_phase(phases, "compile"):
        program = (compile_graph(graph, None, calibration_inputs={"adc": calibration})
                   if motif is None else _motif_program(graph, motif, calibration, report))
        say("bench", "compiled")
        plans = program_plans(program)
    products, rotations = floor_products(plans), rotation_floors(plans)
    report.floor_products = [f"{p.id} ({' x '.join(map(str, p.shape))})" for p in products]
    report.floor_products += [_rotation_text(r) for r in rotations]
    with threadpool_limits(limits=threads):
        with cpu_phase(phases, "conventional"):
            report.seconds["conventional"] = median_s(lambda: evaluate(graph, {"adc": frame}),
                                                      repeats)
        say("bench", "conventional done")
        for mode in modes:
            n = repeats if mode != "step" else (step_repeats or repeats)
            run = {mode: lambda m=mode: run_program(program, {"adc": frame}, mode=m,
                                                    plans=plans, out_of_range="clip")}
            if mode == "closed" and (products or rotations):  # the floor in turn with it
                run.update(floor_calls(products, rotations=rotations))
            with cpu_phase(phases, f"{mode} (with its floor)" if len(run) > 1 else mode):
                report.seconds.update(interleaved_medians(run, n))
            say("bench", f"{mode} done")
        report.peak_rss_gb = _peak_rss_gb()
    if user_path:  # run_program as called, then compile with and without the check
        with threadpool_limits(limits=threads):
            _user_path(program, graph, config, scene, frame, repeats, report, say)
    if brian2 and motif is None:  # last: the GBs it frees keep the kernel busy for a while
        with threadpool_limits(limits=threads), \
                cpu_phase(phases, "range stage: closed, step and Brian2"):
            _range_stage(config, frame, calibration, repeats, report)
        say("bench", "Brian2 done")
    report.cpu_phases["process"] = process_cpu()
    report.load_after = os.getloadavg()
    report.notes.append("simulator figures exclude compilation and plan building (done once)")
    return report


def _motif_program(graph, motif: str, calibration, report: BenchReport):
    """``graph`` compiled with ``MOTIF_CHAINS[motif]`` (no accuracy measurement: only the
    simulator is timed); notes the choice in ``report``."""
    from compiler.compile import compile_graph
    from ir.errors import CompileError

    if motif not in MOTIF_CHAINS:
        raise CompileError(f"bench: motif {motif!r} is not one of {sorted(MOTIF_CHAINS)}")
    target, motifs = MOTIF_CHAINS[motif]
    report.motif = motif
    report.chain = f"{report.chain or graph.name} ({motif} {', '.join(motifs)}, {target})"
    report.notes.append(f"{motif} chain: compiled for {target} with motifs {motifs}; Brian2 "
                        "is timed on the default chain's range stage only")
    return compile_graph(graph, target, motifs=motifs, calibration_inputs={"adc": calibration},
                         accuracy="off")


def _rotation_text(r) -> str:
    """``"id rotations (rows x K x P, steps steps, F-bit)"`` of a resonator floor."""
    kind = f"{r.coef_bits}-bit rotations" if r.coef_bits else "power-table product"
    return f"{r.id} {kind} ({' x '.join(map(str, r.shape[:3]))}, {r.n_steps} steps)"


def chain_inputs(graph, frame):
    """``frame`` cut to the shape of ``graph``'s ``adc`` node (its leading entries per axis).

    Examples
    --------
    >>> import numpy as np
    >>> from ir import Graph
    >>> g = Graph.from_dict({"name": "g", "nodes": [
    ...     {"id": "adc", "op": "adc_input", "shape": {"rx": 2, "sample": 4}, "complex": True},
    ...     {"id": "out", "op": "output", "input": "adc"}]})
    >>> chain_inputs(g, np.zeros((8, 16), complex)).shape
    (2, 4)
    """
    from ir.errors import RadarConfigError

    want = tuple(graph.op("adc").shape.values())
    if len(want) != frame.ndim or any(w > n for w, n in zip(want, frame.shape, strict=True)):
        raise RadarConfigError(f"chain {graph.name!r}: its adc input {want} does not fit inside "
                               f"the preset's frame {frame.shape}; pick a preset with at least "
                               "as many receivers, chirps and samples")
    return frame[tuple(slice(0, w) for w in want)]


def _user_path(program, graph, config, scene, frame, repeats: int, report: BenchReport,
               say) -> None:
    """:mod:`radarsnn.bench_user`'s figures on the bench's program, frame and chain."""
    import numpy as np

    from radar.scene import simulate_frame
    from radarsnn.bench_user import N_FRAMES, cpu_phase, time_compile, time_user_path

    frames = np.stack([chain_inputs(graph, simulate_frame(config, scene, seed=s).adc)
                       for s in range(N_FRAMES)])
    with cpu_phase(report.cpu_phases, "user's path: run_program and the host's threads"):
        time_user_path(program, frame, frames, repeats, report, interleaved_medians)
    say("bench", "user's path done")
    with cpu_phase(report.cpu_phases, "user's path: compile with and without the check"):
        time_compile(graph, frames[1:4], repeats, report, interleaved_medians)
    say("bench", "compile done")
