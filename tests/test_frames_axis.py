"""A leading frames axis on a chain's inputs: ir.evaluate and run_program (issue 19, item 6)."""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import run_program
from compiler.compile import compile_graph
from ir import Graph, evaluate
from ir.errors import IRError
from ir.frames import n_frames
from ir.types import TensorType

RNG = np.random.default_rng(7)


def _range_chain() -> Graph:
    return Graph.from_dict({"name": "r", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 16}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range",
         "keep": "positive"},
        {"id": "m", "op": "magnitude", "input": "f", "kind": "l2"},
        {"id": "o", "op": "output", "input": "m"}]})


def _rd_chain() -> Graph:
    return Graph.from_dict({"name": "rd", "nodes": [
        {"id": "adc", "op": "input", "shape": {"chirp": 8, "sample": 16}, "complex": True},
        {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler"},
        {"id": "mag", "op": "magnitude", "input": "dop", "kind": "square"},
        {"id": "o", "op": "output", "input": "mag"}]})


def test_evaluate_runs_each_frame_as_if_alone():
    g = _range_chain()
    x = RNG.normal(size=(5, 16))
    framed = evaluate(g, {"x": x})
    for i in range(5):
        for node, value in evaluate(g, {"x": x[i]}).items():
            np.testing.assert_array_equal(framed[node][i], value)
    assert framed["o"].shape == (5, 8)


@pytest.mark.parametrize("policy", ["static", "per-input"])
def test_run_program_with_frames_equals_frame_by_frame(policy):
    g = _rd_chain()
    x = RNG.normal(size=(3, 8, 16)) + 1j * RNG.normal(size=(3, 8, 16))
    program = compile_graph(g, target=None, calibration=policy, calibration_inputs={"adc": x})
    seen = []
    framed = run_program(program, {"adc": x}, out_of_range="clip",
                         progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 3), (2, 3), (3, 3)]
    alone = [run_program(program, {"adc": x[i]}, out_of_range="clip") for i in range(3)]
    for i, one in enumerate(alone):
        for node, value in one.values.items():
            np.testing.assert_array_equal(framed.values[node][i], value)
    assert framed.outputs["o"].shape == (3, 8, 16)
    assert framed.spike_counts == {k: sum(a.spike_counts[k] for a in alone)
                                   for k in alone[0].spike_counts}
    assert [s.n_frames for s in framed.simulations] == [3] * len(alone[0].simulations)


def test_empty_mixed_and_misshapen_frames_are_refused():
    g = _range_chain()
    with pytest.raises(IRError, match="length 0"):
        evaluate(g, {"x": np.zeros((0, 16))})
    program = compile_graph(g, target=None, calibration_inputs={"x": RNG.normal(size=16)})
    with pytest.raises(IRError, match="length 0"):
        run_program(program, {"x": np.zeros((0, 16))})
    with pytest.raises(IRError, match=r"does not match the declared axes"):
        run_program(program, {"x": np.zeros((2, 3, 16))})  # two extra axes: not frames
    types = {"a": TensorType(axes={"range": 4}), "b": TensorType(axes={"range": 4})}
    with pytest.raises(IRError, match=r"\['a'\] have a leading frames axis but \['b'\] do not"):
        n_frames(types, {"a": np.zeros((2, 4)), "b": np.zeros(4)})
    with pytest.raises(IRError, match="frame counts differ"):
        n_frames(types, {"a": np.zeros((2, 4)), "b": np.zeros((3, 4))})


def test_radarsnn_run_reads_a_frames_axis(tmp_path, capsys):
    from backends import save
    from radarsnn.cli import main

    g = _range_chain()
    x = RNG.normal(size=(4, 16))
    program = compile_graph(g, target="loihi2", calibration_inputs={"x": x})
    save(program, tmp_path / "art")
    np.save(tmp_path / "x.npy", x)
    assert main(["run", str(tmp_path / "art"), "-i", str(tmp_path / "x.npy"),
                 "-o", str(tmp_path / "y.npz"), "--json"]) == 0
    capsys.readouterr()
    y = np.load(tmp_path / "y.npz")["o"]
    assert y.shape == (4, 8)
    for i in range(4):
        np.testing.assert_array_equal(y[i], run_program(program, {"x": x[i]},
                                                        out_of_range="clip").outputs["o"])
