"""``radarsnn bench``'s user's-path figures (radarsnn.bench_user): present, consistent, printed.

Timings are never asserted (benchmarks/): only that every figure is measured and that the
ratios are those of the figures of the same run.
"""

from __future__ import annotations

import json

import numpy as np

from backends.reference.frames_run import default_parallel
from compiler.compile import compile_graph
from ir import Graph
from radarsnn.bench import BenchReport, interleaved_medians
from radarsnn.bench_user import GOALS, time_compile, time_user_path, user_path_ratios


def _chain() -> Graph:
    return Graph.from_dict({"name": "rd", "nodes": [
        {"id": "adc", "op": "adc_input", "shape": {"rx": 2, "chirp": 8, "sample": 16},
         "complex": True},
        {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler"},
        {"id": "mag", "op": "magnitude", "input": "dop", "kind": "square"},
        {"id": "rd", "op": "sum", "input": "mag", "axis": "rx"},
        {"id": "o", "op": "output", "input": "rd"}]})


def _frames(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return (rng.normal(size=(n, 2, 8, 16)) + 1j * rng.normal(size=(n, 2, 8, 16))) * 100


def test_the_user_path_is_timed_and_its_ratios_are_the_figures():
    frames = _frames(4)
    program = compile_graph(_chain(), None, calibration_inputs={"adc": frames})
    report = BenchReport(preset="p", repeats=1, threads=1, machine="m")
    time_user_path(program, frames[0], frames, 1, report, interleaved_medians)
    time_compile(_chain(), frames[1:4], 1, report, interleaved_medians)
    assert set(report.user_path) == {
        "run_program_first_call", "run_program_frame", "run_program_frame_planned",
        "frames_axis_1_worker", "frames_axis_n_workers", "frames_axis_n_threads",
        "host_blas_1_thread",
        "host_blas_n_threads", "host_stream_1_thread", "host_stream_n_threads",
        "compile_accuracy_off", "compile_accuracy_on"}, report.notes
    assert report.workers >= 1 and report.n_frames_axis == 4
    assert report.parallel == default_parallel()  # run_program's default, reported as run
    assert set(report.cpu) == {"user_s", "system_s", "threads_user_s", "threads_system_s",
                               "warmup_user_s", "warmup_system_s"}
    assert report.cpu["user_s"] > 0 and report.cpu["threads_user_s"] > 0
    ratios = user_path_ratios(report.user_path, report.cpu)
    assert set(ratios) == {*GOALS, "threads_speedup", "host_thread_speedup",
                           "host_stream_speedup"}
    up = report.user_path
    assert ratios["workers_speedup"] == up["frames_axis_1_worker"] / up["frames_axis_n_workers"]
    doc = json.loads(json.dumps(report.to_dict()))
    assert doc["user_path_ratios"] == ratios and doc["user_path"] == up
    text = report.to_text()
    assert "user's path" in text and "workers_speedup" in text and "goal >= 1.7" in text


def test_a_chain_the_target_refuses_is_a_note(monkeypatch):
    import radarsnn
    from ir.errors import BudgetError

    def refuse(graph, target, **kwargs):
        raise BudgetError(f"chain {graph.name!r} does not fit {target}")

    monkeypatch.setattr(radarsnn, "compile_graph", refuse)
    report = BenchReport(preset="p", repeats=1, threads=1, machine="m")
    time_compile(_chain(), _frames(3), 1, report, interleaved_medians)
    assert report.user_path == {}
    assert report.notes == ["compile for kapoho_point not timed: chain 'rd' does not fit "
                            "kapoho_point"]


def test_no_user_path_leaves_its_keys_empty(capsys):
    from radarsnn.cli import main

    assert main(["bench", "--preset", "seed003", "--repeats", "1", "--mode", "closed",
                 "--no-brian2", "--no-user-path", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["user_path"] == {} and doc["user_path_ratios"] == {} and doc["cpu"] == {}
    assert doc["workers"] == 0 and "closed" in doc["seconds"]
