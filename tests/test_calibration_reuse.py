"""A measured compile calibrates once for all its attempts, and compiles the same bytes (issue 35).

The ladder search (:mod:`compiler.accuracy.select`) compiles one configuration after
another on the same calibration frames; the calibrate pass measures the frames for the
first and hands a copy of that record to the next attempts whose chain is the same
(:attr:`compiler.passes.base.CompileContext.calibrations`).  The program chosen must be
the one a compile measuring every attempt chooses, byte for byte.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends import save
from backends.reference import ReferenceSimulator
from compiler.compile import compile_graph
from compiler.passes.base import CompileContext
from compiler.passes.calibrate import Calibrate
from compiler.program import CompiledProgram
from ir import Graph


def _ca_chain() -> Graph:
    return Graph.from_dict({"name": "ca", "nodes": [
        {"id": "p", "op": "input", "shape": {"doppler": 16, "range": 64}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "p", "kind": "ca", "guard": [1, 1],
         "train": [2, 4], "pfa": 1e-3, "edge": ["wrap", "clip"]},
        {"id": "o", "op": "output", "input": "det"}]})


def _maps(seed: int, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    maps = rng.exponential(size=(n, 16, 64)) * 1e6
    for f in range(n):
        for _ in range(3):
            maps[f, rng.integers(16), rng.integers(64)] *= 10 ** rng.uniform(2, 6)
    return maps


def _artifact_bytes(program: CompiledProgram, folder) -> dict[str, bytes]:
    save(program, folder)
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_the_attempts_share_one_measurement_and_compile_the_same_bytes(tmp_path, monkeypatch):
    maps = _maps(3, 4)
    measured = []
    original = Calibrate._measure

    def counted(self, ctx, program):
        measured.append(program.graph.name)
        return original(self, ctx, program)

    monkeypatch.setattr(Calibrate, "_measure", counted)
    shared = compile_graph(_ca_chain(), "loihi2", calibration_inputs={"p": maps},
                           simulator=ReferenceSimulator())
    attempts = shared.records.extra["motif_selection"]["attempts"]
    assert len(attempts) > 1 and len(measured) == 1
    monkeypatch.setattr(Calibrate, "_reused", lambda self, ctx, program: None)
    alone = compile_graph(_ca_chain(), "loihi2", calibration_inputs={"p": maps},
                          simulator=ReferenceSimulator())
    assert len(measured) == 1 + len(attempts)
    assert alone.records.extra["motif_selection"] == shared.records.extra["motif_selection"]
    assert _artifact_bytes(shared, tmp_path / "shared") == _artifact_bytes(alone,
                                                                         tmp_path / "alone")


def _calibrated(ctx: CompileContext, graph: Graph, pass_: Calibrate):
    program = pass_.apply(ctx, CompiledProgram(graph=graph))
    return program.records.calibration


def _same_calibration(a, b) -> None:
    assert a.to_dict() == b.to_dict()
    for node in a.nodes:
        fa, fb = a.nodes[node].frames, b.nodes[node].frames
        assert (fa is None) == (fb is None)
        if fa is not None:
            assert fa.dtype == fb.dtype and fa.tobytes() == fb.tobytes()


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), headroom=st.sampled_from([1.0, 2.0]),
       policy=st.sampled_from(["static", "per-input"]))
def test_a_reused_calibration_is_the_measured_one(seed, headroom, policy):
    inputs = {"p": _maps(seed, 2)}
    pass_ = Calibrate(policy=policy, headroom=headroom)
    memo: list = []
    first = _calibrated(CompileContext(calibration_inputs=inputs, calibrations=memo),
                        _ca_chain(), pass_)
    again = _calibrated(CompileContext(calibration_inputs=inputs, calibrations=memo),
                        _ca_chain(), pass_)
    fresh = _calibrated(CompileContext(calibration_inputs=inputs), _ca_chain(), pass_)
    assert len(memo) == 1 and again is not memo[0][1]
    _same_calibration(again, fresh)
    _same_calibration(first, fresh)


@pytest.mark.parametrize("change", ["graph", "headroom", "policy", "target"])
def test_a_different_chain_or_pass_is_measured_again(change):
    from compiler.hardware import load_profile

    inputs = {"p": _maps(1, 2)}
    memo: list = []
    _calibrated(CompileContext(calibration_inputs=inputs, calibrations=memo,
                               target=load_profile("loihi2")), _ca_chain(), Calibrate())
    target = load_profile("loihi" if change == "target" else "loihi2")
    graph = _ca_chain()
    if change == "graph":
        graph = Graph.from_dict({**graph.to_dict(), "name": "other"})
    pass_ = Calibrate(headroom=2.0 if change == "headroom" else 1.0,
                      policy="per-input" if change == "policy" else "static")
    _calibrated(CompileContext(calibration_inputs=inputs, calibrations=memo, target=target),
                graph, pass_)
    assert len(memo) == 2
    _calibrated(CompileContext(calibration_inputs=inputs, calibrations=memo,
                               target=load_profile("loihi2")), _ca_chain(), Calibrate())
    assert len(memo) == 2  # the first again: reused
