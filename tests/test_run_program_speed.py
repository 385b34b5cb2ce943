"""The user's path kept bit-equal while made fast (issue 35): cached plans, frames on threads.

* a program run twice (the second time on the plans kept from the first,
  :mod:`backends.reference.plan_cache`) returns the same bits as a run on freshly built
  plans; a network whose parts are replaced gets a new plan;
* a frames axis run on 1, 2 or 3 threads (``workers``, :mod:`backends.reference.frames_run`)
  returns the same bits as the frames run one by one;
* the errors of the new options name the field, the value and the fix.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference import RunOptions, SimResult, program_plans, run_program
from backends.reference.frames_run import FrameStack, map_frames, resolve_workers
from backends.reference.plan_cache import cached_plan, forget_plan, peek_plan
from compiler.compile import compile_graph
from ir import Graph
from ir.errors import SimulationError


def _rd_chain() -> Graph:
    return Graph.from_dict({"name": "rd", "nodes": [
        {"id": "adc", "op": "input", "shape": {"chirp": 8, "sample": 16}, "complex": True},
        {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler"},
        {"id": "mag", "op": "magnitude", "input": "dop", "kind": "square"},
        {"id": "det", "op": "cfar", "input": "mag", "kind": "os", "axes": ["range", "doppler"],
         "guard": [1, 1], "train": [2, 1], "k": 20, "pfa": 1e-2},
        {"id": "o", "op": "output", "input": "det"}]})


def _frames(seed: int, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 8, 16)) + 1j * rng.normal(size=(n, 8, 16))


PROGRAM = compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(0, 3)})


def _bits(a: np.ndarray) -> bytes:
    a = np.ascontiguousarray(a)
    return a.dtype.str.encode() + str(a.shape).encode() + a.tobytes()


def _same_run(a, b) -> None:
    assert list(a.values) == list(b.values) and list(a.outputs) == list(b.outputs)
    for k in a.values:
        assert _bits(a.values[k]) == _bits(b.values[k]), k
    assert a.spike_counts == b.spike_counts and a.synaptic_events == b.synaptic_events
    assert a.clipped == b.clipped and a.normalized == b.normalized
    for sa, sb in zip(a.simulations, b.simulations, strict=True):
        assert sa.n_frames == sb.n_frames and sa.mode == sb.mode
        for k in sa.first_spike_steps:
            assert _bits(sa.first_spike_steps[k]) == _bits(sb.first_spike_steps[k]), k


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([0.25, 1.0, 4.0]),
       mode=st.sampled_from(["auto", "step"]))
def test_cached_plans_give_the_bits_of_fresh_plans(seed, scale, mode):
    x = _frames(seed, 1)[0] * scale
    cached = [run_program(PROGRAM, {"adc": x}, mode=mode, out_of_range="clip")
              for _ in range(2)]  # the second on the plans the first kept
    fresh = run_program(PROGRAM, {"adc": x}, mode=mode, out_of_range="clip",
                        plans=program_plans(PROGRAM))
    _same_run(cached[0], fresh)
    _same_run(cached[1], fresh)
    assert all(peek_plan(net, "float64") is not None for net in PROGRAM.networks)


def test_a_replaced_part_builds_a_new_plan_and_forget_drops_it():
    program = compile_graph(_rd_chain(), target=None,
                            calibration_inputs={"adc": _frames(1, 2)})
    net = program.networks[0]
    plan = cached_plan(net, "float64")
    assert cached_plan(net, "float64") is plan and peek_plan(net, "int64") is None
    net.projections = list(net.projections)  # the same objects: still current
    assert peek_plan(net, "float64") is plan
    net.projections = [*net.projections[1:], net.projections[0]]  # another order: stale
    assert len(net.projections) > 1 and peek_plan(net, "float64") is None
    again = cached_plan(net, "float64")
    assert again is not plan and cached_plan(net, "float64") is again
    assert [d for d in again.deliveries] == [q.id for q in net.projections]
    forget_plan(net)
    assert peek_plan(net, "float64") is None


def test_kept_plans_die_with_their_network_and_copies_start_without_them():
    """A plan refers to its network: kept anywhere but on the network, every network ever
    run (and its plans, hundreds of MB for a radar chain) would stay alive."""
    import copy
    import dataclasses
    import gc
    import weakref

    program = compile_graph(_rd_chain(), target=None,
                            calibration_inputs={"adc": _frames(2, 2)})
    run_program(program, {"adc": _frames(3, 1)[0]}, out_of_range="clip")
    net = program.networks[0]
    plan = peek_plan(net, "float64")
    assert plan is not None and plan.network is net
    for twin in (copy.copy(net), copy.deepcopy(net), dataclasses.replace(net)):
        assert peek_plan(twin, "float64") is None
    alive = [weakref.ref(x) for x in (program, net, plan)]
    gc.disable()  # freed at once, by reference counts: no cycle waits for the collector
    try:
        del program, net, plan, twin
        assert [r() for r in alive] == [None, None, None]
    finally:
        gc.enable()


def test_compiling_with_the_accuracy_check_keeps_no_network_alive():
    """The check simulates the program it measures; afterwards no network it made (nor
    their plans) is left behind, however many times one compiles."""
    import gc
    import weakref

    from radarsnn import compile_graph as compile_checked  # with the reference simulator

    def networks() -> set[int]:
        gc.collect()
        return {id(o) for o in gc.get_objects() if type(o).__name__ == "SpikingNetwork"}

    cal = {"adc": _frames(4, 3)}
    before, kept = networks(), []
    for _ in range(2):
        program = compile_checked(_rd_chain(), "kapoho_point", calibration_inputs=cal)
        assert program.records.accuracy is not None
        kept += [weakref.ref(n) for n in program.networks]
        del program
    assert networks() <= before and [r() for r in kept] == [None] * len(kept)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 5), workers=st.sampled_from([1, 2, 3]))
def test_frames_on_threads_give_the_bits_of_frame_by_frame(seed, n, workers):
    x = _frames(seed, n)
    seen = []
    framed = run_program(PROGRAM, {"adc": x}, out_of_range="clip", workers=workers,
                         progress=lambda done, total: seen.append((done, total)))
    assert seen == [(i + 1, n) for i in range(n)]
    alone = [run_program(PROGRAM, {"adc": x[i]}, out_of_range="clip") for i in range(n)]
    for node, value in framed.values.items():
        assert value.shape[0] == n
        for i in range(n):
            assert _bits(value[i]) == _bits(alone[i].values[node]), (node, i)
    assert framed.spike_counts == {k: sum(a.spike_counts[k] for a in alone)
                                   for k in alone[0].spike_counts}
    one = run_program(PROGRAM, {"adc": x}, options=RunOptions(out_of_range="clip", workers=1))
    _same_run(framed, one)
    _same_sims(framed.simulations, [SimResult.stack([a.simulations[k] for a in alone])
                                    for k in range(len(alone[0].simulations))])


def _same_sims(got, want) -> None:
    assert len(got) == len(want)
    for a, b in zip(got, want, strict=True):
        for name in ("outputs", "first_spike_steps", "spikes"):
            x, y = getattr(a, name), getattr(b, name)
            assert (x is None) == (y is None) and list(x or ()) == list(y or ()), name
            for k in x or ():
                assert _bits(x[k]) == _bits(y[k]), (name, k)
        for name in ("spike_counts", "synaptic_events", "mode", "arithmetic", "n_steps",
                     "n_frames", "clipped", "state_overflow"):
            assert getattr(a, name) == getattr(b, name), name


def test_recorded_rasters_over_threads_are_the_frames_rasters():
    x = _frames(6, 3)
    framed = run_program(PROGRAM, {"adc": x}, out_of_range="clip", workers=2, mode="step",
                         record_spikes=True)
    alone = [run_program(PROGRAM, {"adc": x[i]}, out_of_range="clip", mode="step",
                         record_spikes=True) for i in range(3)]
    assert all(s.spikes for s in framed.simulations)
    _same_sims(framed.simulations, [SimResult.stack([a.simulations[k] for a in alone])
                                    for k in range(len(alone[0].simulations))])


def test_per_input_frames_on_threads_keep_their_peaks():
    program = compile_graph(_rd_chain(), target=None, calibration="per-input",
                            calibration_inputs={"adc": _frames(2, 3)})
    x = _frames(3, 4) * np.array([1.0, 10.0, 0.1, 3.0])[:, None, None]
    one = run_program(program, {"adc": x}, out_of_range="clip", workers=1)
    two = run_program(program, {"adc": x}, out_of_range="clip", workers=2)
    _same_run(one, two)
    assert list(one.input_peaks) == list(two.input_peaks) == ["adc"]
    assert _bits(one.input_peaks["adc"]) == _bits(two.input_peaks["adc"])


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_bad_workers_are_refused_naming_the_field(workers):
    with pytest.raises(SimulationError, match=r"program 'rd': workers=.* must be a whole "
                                              r"number >= 1 \(threads for a frames axis\)"):
        run_program(PROGRAM, {"adc": _frames(0, 1)[0]}, workers=workers)


def test_an_error_in_a_frame_on_a_thread_is_raised():
    x = _frames(4, 4)
    x[2] *= 1e6  # far beyond the calibrated range: refused under "reject"
    for workers in (1, 2):
        with pytest.raises(SimulationError, match="range"):
            run_program(PROGRAM, {"adc": x}, workers=workers)


def test_frame_stack_refuses_frames_that_differ():
    stack = FrameStack(2)
    stack.put(0, {"y": np.zeros(2)}, where="program 'p'")
    with pytest.raises(SimulationError, match=r"node 'y' is float32\[2\] in frame 1 but "
                                              r"float64\[2\] in another"):
        stack.put(1, {"y": np.zeros(2, np.float32)}, where="program 'p'")
    with pytest.raises(SimulationError, match="frame 1 has the values"):
        stack.put(1, {"z": np.zeros(2)}, where="program 'p'")


def test_map_frames_raises_the_earliest_failure_and_resolves_workers():
    def run(i):
        if i in (1, 3):
            raise ValueError(f"frame {i}")

    with pytest.raises(ValueError, match="frame 1"):
        map_frames(run, 4, 1)
    with pytest.raises(ValueError, match="frame [13]"):
        map_frames(run, 4, 2)
    assert resolve_workers(8, 3) == 3 and resolve_workers(1, 9) == 1
    assert resolve_workers(None, 1) == 1


def test_radarsnn_run_workers_and_parallel_flags(tmp_path, capsys):
    from backends import save
    from radarsnn.cli import main

    save(PROGRAM, tmp_path / "art")
    x = _frames(5, 3)
    np.save(tmp_path / "x.npy", x)
    outs = []
    for n, kind in (("1", "auto"), ("2", "threads"), ("2", "processes"), ("2", "auto")):
        out = tmp_path / f"y{n}{kind}.npz"
        assert main(["run", str(tmp_path / "art"), "-i", str(tmp_path / "x.npy"), "--clip",
                     "--workers", n, "--parallel", kind, "-o", str(out), "-q"]) == 0
        outs.append(np.load(out)["o"])
    assert all(_bits(o) == _bits(outs[0]) for o in outs) and outs[0].shape[0] == 3
    assert main(["run", str(tmp_path / "art"), "-i", str(tmp_path / "x.npy"),
                 "--workers", "0"]) == 2
    assert "argument --workers: 0 is not a whole number >= 1" in capsys.readouterr().err


def test_a_decoded_value_is_one_array_in_values_and_in_its_segment_result():
    """As in a one-frame run, a decoded output the program keeps as is shares its array."""
    x = _frames(7, 3)
    one = run_program(PROGRAM, {"adc": x[0]}, out_of_range="clip")
    framed = run_program(PROGRAM, {"adc": x}, out_of_range="clip", workers=2)
    for a, b in zip(one.simulations, framed.simulations, strict=True):
        for port, value in a.outputs.items():
            assert (value is one.values.get(port)) == (b.outputs[port] is framed.values.get(port))
    assert any(v is framed.values.get(p) for s in framed.simulations for p, v in s.outputs.items())


def test_threads_running_one_new_network_build_its_plan_once(monkeypatch):
    import threading

    from backends.reference import plan_cache

    program = compile_graph(_rd_chain(), target=None, calibration_inputs={"adc": _frames(8, 2)})
    built = []
    original = plan_cache.build_plan

    def counted(network, arithmetic):
        built.append(network.name)
        return original(network, arithmetic)

    monkeypatch.setattr(plan_cache, "build_plan", counted)
    barrier = threading.Barrier(3)

    def get():
        barrier.wait()
        return [cached_plan(net, "float64") for net in program.networks]

    results = []
    threads = [threading.Thread(target=lambda: results.append(get())) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(built) == len(program.networks) and len(results) == 3
    assert all(r[k] is results[0][k] for r in results for k in range(len(r)))


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 5), workers=st.sampled_from([2, 3]))
def test_frames_on_processes_give_the_bits_of_one_thread(seed, n, workers):
    from backends.reference.frames_memory import fork_available

    if not fork_available():  # threads there: the same bits, tested above
        return
    x = _frames(seed, n)
    seen = []
    forked = run_program(PROGRAM, {"adc": x}, options=RunOptions(
        out_of_range="clip", workers=workers, parallel="processes"),
        progress=lambda done, total: seen.append((done, total)))
    one = run_program(PROGRAM, {"adc": x}, out_of_range="clip", workers=1)
    assert seen == [(i + 1, n) for i in range(n)]
    _same_run(forked, one)
    _same_sims(forked.simulations, one.simulations)


def test_a_frame_failing_in_a_process_raises_its_own_error_here():
    x = _frames(4, 4)
    x[2] *= 1e6
    options = RunOptions(workers=2, parallel="processes")
    with pytest.raises(SimulationError, match="range") as forked:
        run_program(PROGRAM, {"adc": x}, options=options)
    with pytest.raises(SimulationError, match="range") as alone:
        run_program(PROGRAM, {"adc": x[2]})
    assert str(forked.value) == str(alone.value)


def test_parallel_must_be_auto_threads_or_processes():
    with pytest.raises(SimulationError, match=r"parallel='gpu' is not one of \('auto', "
                                              r"'threads', 'processes'\)"):
        run_program(PROGRAM, {"adc": _frames(0, 2)}, options=RunOptions(parallel="gpu"))
