"""Option and profile values that cannot work are typed errors naming the least value that
does: the resonator's stream bits (an all-zero stream) and decay (a gain of 0), a graded
spike payload of one bit (a division by zero)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.hardware import load_profile
from ir import Graph
from ir.errors import CompileError

N = 64


def _graph(n: int = N) -> Graph:
    return Graph.from_dict({"name": "res", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 3, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})


def _signal(n: int = N) -> np.ndarray:
    t = np.arange(n)
    return np.random.default_rng(0).normal(size=(3, n)) + 3 * np.cos(2 * np.pi * 5 * t / n)


def _resonator(target, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the drift warning of a coarse stream
        return compile_graph(_graph(), target, motifs={"f": "resonator"},
                             calibration_inputs={"x": _signal()}, time_steps=256,
                             options=options)


@pytest.mark.parametrize("target", ["unbounded", "loihi2"])
def test_one_stream_bit_is_refused_with_the_least_that_streams_the_peak(target):
    # the encoder range is twice the calibrated peak: one level leaves the peak at 0.5 -> 0
    with pytest.raises(CompileError, match=r"stream_bits=1 .* stream_bits >= 2"):
        _resonator(target, stream_bits=1)
    y = run_program(_resonator(target, stream_bits=2), {"x": _signal()}).outputs["o"]
    assert np.abs(y).max() > 0


@pytest.mark.parametrize("decay", [1e-300, 5e-324, 1e-4])
@pytest.mark.parametrize("target", ["loihi", "loihi2"])
def test_a_decay_below_one_coefficient_step_is_refused(target, decay):
    with pytest.raises(CompileError, match=r"resonator_decay=.* resonator_decay >= 0.000244"):
        _resonator(target, resonator_decay=decay)


def test_a_decay_above_the_bound_compiles_to_finite_values():
    y = run_program(_resonator("loihi2", resonator_decay=1e-3), {"x": _signal()}).outputs["o"]
    assert np.isfinite(y).all() and np.abs(y).max() > 0


def test_a_one_bit_graded_payload_is_a_profile_error(tmp_path):
    text = load_profile("loihi2").model_dump()
    lines = [f"{k}: {'null' if v is None else str(v).lower() if isinstance(v, bool) else v}"
             for k, v in {**text, "graded_spike_bits": 1}.items()]
    path = tmp_path / "one_bit.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(CompileError, match=r"graded_spike_bits.* = 1: .*equal to 2"):
        load_profile(path)
    two = load_profile("loihi2").model_copy(update={"graded_spike_bits": 2})
    rng = np.random.default_rng(4)
    g = Graph.from_dict({"name": "g", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 32}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})
    p = compile_graph(g, two, calibration_inputs={"x": rng.normal(size=(3, 2, 32))},
                      time_steps=32)
    assert p.networks[0].meta["charging"]["f"]["payload_bits"] == 2


def test_a_headroom_that_overflows_the_range_is_a_compile_error():
    # 1e308 x the calibrated peak is inf: the input code cannot be built
    rng = np.random.default_rng(0)
    with pytest.raises(CompileError, match=r"node 'f' \(motif time\): .* headroom=1e\+308"):
        compile_graph(_graph(), "loihi", calibration_inputs={"x": rng.normal(size=(3, N))},
                      options={"headroom": 1e308})


def test_fft_radices_that_do_not_multiply_to_the_size_name_the_node_and_option():
    g = Graph.from_dict({"name": "fft", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 32}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample"},
        {"id": "o", "op": "output", "input": "f"}]})
    x = np.random.default_rng(0).normal(size=(3, 32))
    with pytest.raises(CompileError, match=r"node 'f' \(time-fft\): fft_radices=\[4, 4\] .* 32"):
        compile_graph(g, "loihi", motifs={"f": "time-fft"}, calibration_inputs={"x": x},
                      options={"fft_radices": [4, 4]})
