"""``radarsnn bench``: the user's path — what ``run_program`` and ``compile_graph`` cost as called.

The bench's ``closed`` figure runs the closed form with plans built in advance; a user
calls :func:`backends.reference.run_program` on one frame after another, or on a frames
axis, and compiles with the accuracy check on.  :func:`time_user_path` times, on the
bench's program and frame, each pair of a ratio *in turn* (the bench's
``interleaved_medians``, passed in as ``medians``):

* ``run_program_frame``: ``run_program(program, {"adc": frame})`` as a user writes it (the
  plans built by the first call and kept, :mod:`backends.reference.plan_cache`), against
  ``run_program_frame_planned``: the bench's own call (``mode="closed"``, ``plans=`` given);
  ``run_program_first_call``: the very first call, plans built (one run, not a median);
* ``frames_axis_1_worker`` / ``frames_axis_n_workers``: seconds per frame of one call on
  ``n_frames`` frames stacked on a leading axis, with ``workers=1`` and with one worker
  per available core (``workers``), of the kind ``run_program`` uses by default
  (``parallel``: :func:`backends.reference.frames_run.default_parallel`), and
  ``frames_axis_n_threads``: the same workers as threads (``parallel="threads"``), all
  three in turn;
* the user and system CPU seconds of the timed calls of the first two (``cpu.user_s``,
  ``cpu.system_s``) and of the threads (``cpu.threads_user_s``, ``cpu.threads_system_s``),
  and of the three warm-up calls, which fork the worker processes and page their memory in
  (``cpu.warmup_user_s``, ``cpu.warmup_system_s``), worker processes included
  (``resource.getrusage`` and :func:`~backends.reference.frames_pool.workers_cpu_s`:
  system time is mostly page faults);
* what the host allows threads right now: ``host_blas_1_thread`` / ``host_blas_n_threads``,
  ``workers`` series of plain BLAS products (one thread each) run one after the other and
  side by side, in turn; their ratio ``host_thread_speedup`` is what a second core gives
  on this host at this time to work that stays in the cache (1 when
  other work fills the cores); ``host_stream_1_thread`` / ``host_stream_n_threads`` and
  ``host_stream_speedup``, the same for element-wise passes over operands too large for the
  cache: what the memory lets several cores gain, the ceiling of work bound by it;
* :func:`time_compile`: ``compile_accuracy_off`` / ``compile_accuracy_on``:
  :func:`radarsnn.compile_graph` of the chain for ``kapoho_point`` on three calibration
  frames, with ``accuracy="off"`` and with the accuracy check (the default).

Examples
--------
>>> sorted(user_path_ratios({"run_program_frame": 0.03, "run_program_frame_planned": 0.025,
...                          "frames_axis_1_worker": 0.04, "frames_axis_n_workers": 0.025},
...                         {"user_s": 2.0, "system_s": 0.1}))
['run_program_frame_over_planned', 'system_over_user', 'workers_speedup']
>>> user_path_ratios({"host_blas_1_thread": 2.0, "host_blas_n_threads": 1.0}, {})
{'host_thread_speedup': 2.0}
"""

from __future__ import annotations

import contextlib
import resource
from collections.abc import Callable, Iterator

import numpy as np

__all__ = ["GOALS", "cpu_phase", "phase_lines", "phase_ratios", "time_compile",
           "time_user_path", "user_path_lines", "user_path_ratios"]

#: ``medians({name: fn}, repeats) -> {name: seconds}``, each fn timed in turn.
Medians = Callable[[dict[str, Callable[[], object]], int], dict[str, float]]
#: The goals of the user's-path ratios (printed next to them).
GOALS = {"run_program_frame_over_planned": "goal <= 1.2", "workers_speedup": "goal >= 1.7",
         "system_over_user": "goal <= 0.1", "compile_accuracy_on_over_off": "goal <= 2"}
#: Frames on the frames axis timed.
N_FRAMES = 8
#: float64 entries of each operand of the host's streaming passes (16 MiB: past the caches).
STREAM_ENTRIES = 1 << 21
#: The target the compile figures are measured for (the README's quick start).
COMPILE_TARGET = "kapoho_point"


def _cpu() -> tuple[float, float]:
    """User and system CPU seconds of this process and of its worker processes, live
    (:func:`~backends.reference.frames_pool.workers_cpu_s`) or ended."""
    from backends.reference.frames_pool import workers_cpu_s

    r = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    user, system = workers_cpu_s()
    return r.ru_utime + c.ru_utime + user, r.ru_stime + c.ru_stime + system


@contextlib.contextmanager
def cpu_phase(phases: dict[str, dict[str, float]], name: str) -> Iterator[None]:
    """Add the user and system CPU seconds spent inside the block (this process, its ended
    children and its live worker processes) to ``phases[name]``."""
    before = _cpu()
    try:
        yield
    finally:
        after = _cpu()
        got = phases.setdefault(name, {"user_s": 0.0, "system_s": 0.0})
        got["user_s"] += after[0] - before[0]
        got["system_s"] += after[1] - before[1]


def process_cpu() -> dict[str, float]:
    """User and system CPU seconds of the whole process so far (imports included), its
    ended children and live worker processes."""
    user, system = _cpu()
    return {"user_s": user, "system_s": system}


def phase_ratios(phases: dict[str, dict[str, float]]) -> dict[str, float]:
    """``system_s / user_s`` of every phase that spent user time.

    Examples
    --------
    >>> phase_ratios({"closed": {"user_s": 2.0, "system_s": 0.1}, "x": {"user_s": 0.0,
    ...                                                                  "system_s": 0.0}})
    {'closed': 0.05}
    """
    return {k: v["system_s"] / v["user_s"] for k, v in phases.items() if v["user_s"] > 0}


def phase_lines(phases: dict[str, dict[str, float]]) -> list[str]:
    """The table lines of the CPU by phase (empty when none was measured)."""
    if not phases:
        return []
    lines = [f"  CPU by phase (this process, children, workers) {'user s':>9} {'system s':>9} "
             f"{'sys/user':>9}"]
    ratios = phase_ratios(phases)
    for k, v in phases.items():
        lines.append(f"  {k:<47} {v['user_s']:>9.2f} {v['system_s']:>9.2f} "
                     f"{ratios.get(k, float('nan')):>9.2f}")
    return lines


def time_user_path(program, frame: np.ndarray, frames: np.ndarray, repeats: int, report,
                   medians: Medians) -> None:
    """Fill ``report.user_path``, ``report.workers`` and ``report.cpu`` (module docstring)."""
    import time

    from backends.reference import program_plans, run_program
    from backends.reference.frames_run import available_cores, default_parallel
    from backends.reference.heap import held

    inputs, stacked = {"adc": frame}, {"adc": frames}
    t0 = time.perf_counter()
    run_program(program, inputs, out_of_range="clip")  # builds and keeps the plans
    report.user_path["run_program_first_call"] = time.perf_counter() - t0
    plans = program_plans(program)
    report.user_path.update(medians({
        "run_program_frame": lambda: run_program(program, inputs, out_of_range="clip"),
        "run_program_frame_planned": lambda: run_program(program, inputs, mode="closed",
                                                         plans=plans, out_of_range="clip")},
        repeats))
    workers = available_cores()
    report.workers, report.n_frames_axis = workers, len(frames)
    report.parallel = default_parallel()
    report.freed_memory_held = held() is not None
    spent: dict[str, dict[str, float]] = {}

    def counted(kind: str, run: Callable[[], object]) -> Callable[[], object]:
        calls = [0]

        def call() -> object:  # each series' own CPU seconds, however the calls interleave
            series = "warmup" if calls[0] == 0 else kind  # the first call forks the workers
            calls[0] += 1
            with cpu_phase(spent, series):
                return run()
        return call

    per_call = medians({
        "frames_axis_1_worker": counted("default", lambda: run_program(
            program, stacked, out_of_range="clip", workers=1)),
        "frames_axis_n_workers": counted("default", lambda: run_program(
            program, stacked, out_of_range="clip", workers=workers)),
        "frames_axis_n_threads": counted("threads", lambda: run_program(
            program, stacked, out_of_range="clip", workers=workers, parallel="threads"))},
        repeats)
    report.user_path.update({k: v / len(frames) for k, v in per_call.items()})
    for series, prefix in (("default", ""), ("threads", "threads_"), ("warmup", "warmup_")):
        got = spent.get(series, {"user_s": 0.0, "system_s": 0.0})
        report.cpu.update({prefix + k: v for k, v in got.items()})
    report.user_path.update(_host_threads(workers, repeats, medians))


def _host_threads(workers: int, repeats: int, medians: Medians) -> dict[str, float]:
    """Seconds of ``workers`` series of BLAS products, and of ``workers`` series of streaming
    element-wise passes, one after the other and on threads."""
    import threading

    a = np.random.default_rng(0).random((512, 512))
    streams = [(np.ones(STREAM_ENTRIES), np.empty(STREAM_ENTRIES)) for _ in range(workers)]

    def products(_k: int = 0) -> None:  # compute-bound: the operands stay in the cache
        for _ in range(8):
            a @ a

    def passes(k: int = 0) -> None:  # memory-bound: 16 MiB operands, read and written
        x, y = streams[k]
        for _ in range(8):
            np.multiply(x, 1.0, out=y)
            np.add(y, x, out=x)

    def side_by_side(series: Callable[[int], None]) -> Callable[[], None]:
        def run() -> None:
            threads = [threading.Thread(target=series, args=(k,)) for k in range(workers)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        return run

    return medians({"host_blas_1_thread": lambda: [products() for _ in range(workers)],
                    "host_blas_n_threads": side_by_side(products),
                    "host_stream_1_thread": lambda: [passes(k) for k in range(workers)],
                    "host_stream_n_threads": side_by_side(passes)}, repeats)


def time_compile(graph, calibration: np.ndarray, repeats: int, report,
                 medians: Medians) -> None:
    """``compile_accuracy_off`` / ``_on`` in ``report.user_path``, in turn (a note if the
    chain cannot be compiled for :data:`COMPILE_TARGET`)."""
    from ir.errors import RadarSNNError
    from radarsnn import compile_graph

    cal = {"adc": calibration}
    try:
        report.user_path.update(medians({
            "compile_accuracy_off": lambda: compile_graph(graph, COMPILE_TARGET,
                                                          calibration_inputs=cal,
                                                          accuracy="off"),
            "compile_accuracy_on": lambda: compile_graph(graph, COMPILE_TARGET,
                                                         calibration_inputs=cal)},
            max(1, min(repeats, 3))))
    except RadarSNNError as err:
        report.notes.append(f"compile for {COMPILE_TARGET} not timed: "
                            f"{' '.join(str(err).split())[:200]}")
        return
    report.notes.append(f"compile figures: radarsnn.compile_graph for {COMPILE_TARGET} on "
                        f"{len(calibration)} calibration frames (the last held back for the "
                        "accuracy check), median of " + str(max(1, min(repeats, 3))))


def user_path_ratios(user_path: dict[str, float], cpu: dict[str, float]) -> dict[str, float]:
    """The user's-path ratios of the figures present (:data:`GOALS`)."""
    out = {}
    pairs = {"run_program_frame_over_planned": ("run_program_frame", "run_program_frame_planned"),
             "workers_speedup": ("frames_axis_1_worker", "frames_axis_n_workers"),
             "threads_speedup": ("frames_axis_1_worker", "frames_axis_n_threads"),
             "host_thread_speedup": ("host_blas_1_thread", "host_blas_n_threads"),
             "host_stream_speedup": ("host_stream_1_thread", "host_stream_n_threads"),
             "compile_accuracy_on_over_off": ("compile_accuracy_on", "compile_accuracy_off")}
    for name, (a, b) in pairs.items():
        if user_path.get(a) and user_path.get(b):
            out[name] = user_path[a] / user_path[b]
    if cpu.get("user_s"):
        out["system_over_user"] = cpu.get("system_s", 0.0) / cpu["user_s"]
    return out


def user_path_lines(report) -> list[str]:
    """The table lines of the user's path (empty when it was not timed)."""
    if not report.user_path:
        return []
    lines = [f"  user's path (run_program as called; frames axis of {report.n_frames_axis}, "
             f"{report.workers} worker(s) = available cores, "
             f"{report.parallel or 'threads'} by default; freed memory "
             f"{'held' if report.freed_memory_held else 'not held'})"]
    for k, v in report.user_path.items():
        rate = ("" if k.startswith(("compile", "host")) else
                f" {1.0 / v if v else float('inf'):>10.2f}")
        lines.append(f"  {k:<28} {v:>10.4f}{rate}")
    if report.cpu:
        lines.append(f"  frames-axis CPU: user {report.cpu['user_s']:.2f} s, system "
                     f"{report.cpu['system_s']:.2f} s")
        for prefix, what in (("threads_", "on threads"), ("warmup_", "of the warm-up calls")):
            if f"{prefix}user_s" in report.cpu:
                lines.append(f"  frames-axis CPU {what}: user "
                             f"{report.cpu[prefix + 'user_s']:.2f} s, system "
                             f"{report.cpu[prefix + 'system_s']:.2f} s")
    for k, v in user_path_ratios(report.user_path, report.cpu).items():
        lines.append(f"  {k:<32} {v:>8.2f}  {GOALS.get(k, '')}")
    return lines
