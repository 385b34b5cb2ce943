"""Spiking magnitude motifs (l1, α-max-β-min) on the S-FT's ± parts, and their error vs |z|."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.reference import run_program, simulate
from compiler.compile import lower_pass
from compiler.lowering import default_registry
from compiler.lowering.magnitude import ALPHA, BETA, amb, l1
from compiler.passes import CompileContext, Verify, run_pipeline
from compiler.passes.calibrate import Calibrate
from compiler.passes.fuse_linear import FuseLinear
from compiler.program import CompiledProgram
from ir import Graph, evaluate
from ir.errors import CompileError

# subnormals excluded: |z| of a subnormal has no relative precision to bound against
_finite = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False)


def compile_mag(graph: Graph, x: np.ndarray, motif: str, **options) -> CompiledProgram:
    options = {"time_steps": 128, "motifs": {"mag": motif}, "encoder_headroom": 1,
               **options}  # hand-worked spike steps
    ctx = CompileContext(calibration_inputs={"x": x}, lowering=default_registry())
    return run_pipeline([Verify(), FuseLinear(), Calibrate(), lower_pass(options)], ctx,
                        CompiledProgram(graph=graph))


def mag_graph(*, with_dft: bool, kind: str = "l2") -> Graph:
    nodes = [{"id": "x", "op": "input", "shape": {"chirp": 4, "sample": 16}, "complex": True}]
    if with_dft:
        nodes.append({"id": "f", "op": "dft", "input": "x", "axis": "sample"})
    nodes += [{"id": "mag", "op": "magnitude", "input": "f" if with_dft else "x", "kind": kind},
              {"id": "o", "op": "output", "input": "mag"}]
    return Graph.from_dict({"name": "m", "nodes": nodes})


def _x(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(4, 16)) + 1j * rng.normal(size=(4, 16))


@given(re=_finite, im=_finite)
def test_error_against_modulus(re: float, im: float) -> None:
    """l1 ∈ [1, √2]·|z|; α-max-β-min ∈ [α, √(α²+β²)]·|z| = [0.9609, 1.0403]·|z|."""
    z = np.array([re + 1j * im])
    r = np.abs(z)
    assert np.all(l1(z) >= r * (1 - 1e-12)) and np.all(l1(z) <= np.sqrt(2) * r * (1 + 1e-12))
    assert np.all(amb(z) >= ALPHA * r * (1 - 1e-12))
    assert np.all(amb(z) <= np.hypot(ALPHA, BETA) * r * (1 + 1e-12))
    assert (ALPHA + BETA) / np.sqrt(2) >= ALPHA  # the minimum is at 0°, not 45°
    assert 0.9609 < ALPHA and np.hypot(ALPHA, BETA) < 1.0403


def test_amb_hand_worked() -> None:
    """3 + 4i: α·4 + β·3 = (492 + 153)/128 = 5.0390625 (true 5)."""
    assert amb(np.array([3 + 4j])).tolist() == [645 / 128]


@pytest.mark.parametrize("motif", ["l1", "amb"])
@pytest.mark.parametrize("with_dft", [False, True])
def test_spiking_magnitude_matches_its_formula_and_step(motif: str, with_dft: bool) -> None:
    g = mag_graph(with_dft=with_dft)
    x = _x(1)
    p = compile_mag(g, x, motif, charging="constant")
    assert p.host_nodes == ["o"]
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    np.testing.assert_array_equal(y, run_program(p, {"x": x}, mode="step").outputs["o"])
    z = evaluate(g, {"x": x})["f" if with_dft else "x"]
    want = {"l1": l1, "amb": amb}[motif](z)
    err = np.abs(y - want).max() / want.max()
    assert err < 0.05, err  # time-code rounding at T = 128 over one or two layers
    true_err = np.abs(y - np.abs(z)).max() / np.abs(z).max()
    assert true_err < (0.45 if motif == "l1" else 0.08)


def test_relay_fires_at_the_earliest_part() -> None:
    """z = 0.25 − 1i, T = 8, X = 1 (s = 1/8): Re⁺ at 8 − 2 = 6, Im⁻ at 8 − 8 = 0 → relay at 0."""
    g = Graph.from_dict({"name": "m", "nodes": [
        {"id": "x", "op": "input", "shape": {"k": 1}, "complex": True},
        {"id": "mag", "op": "magnitude", "input": "x"},
        {"id": "o", "op": "output", "input": "mag"}]})
    x = np.array([0.25 - 1j])
    p = compile_mag(g, x, "amb", time_steps=8, charging="constant")
    r = simulate(p.networks[0], {"x": x}, mode="step")
    assert r.first_spike_steps["mag/in"][0].tolist() == [[6, -1, -1, 0]]
    assert r.first_spike_steps["mag/max"][0].tolist() == [[0]]
    # α·1 + β·0.25 = 1.0605 (full scale √(α²+β²)·|z| = 1.0749): within one output step.
    full = np.hypot(ALPHA, BETA) * abs(x[0])
    assert abs(r.outputs["mag"][0] - amb(x)[0]) <= full / 8


def test_square_kind_and_real_input_are_refused() -> None:
    x = _x()
    with pytest.raises(CompileError, match="square"):
        compile_mag(mag_graph(with_dft=True, kind="square"), x, "l1")
    g = Graph.from_dict({"name": "m", "nodes": [
        {"id": "x", "op": "input", "shape": {"k": 4}},
        {"id": "mag", "op": "magnitude", "input": "x"},
        {"id": "o", "op": "output", "input": "mag"}]})
    with pytest.raises(CompileError, match="complex input"):
        compile_mag(g, np.ones(4), "amb")


def test_companding_magnitude_closed_equals_step() -> None:
    g = mag_graph(with_dft=True)
    x = _x(3) * np.exp(-np.arange(16) / 3)
    p = compile_mag(g, x, "amb", charging="companding")
    assert p.networks[0].meta["charging"]["mag"]["kind"] == "companding"
    assert p.networks[0].meta["charging"]["f"]["kind"] == "constant"
    a = run_program(p, {"x": x}, mode="closed").outputs["o"]
    np.testing.assert_array_equal(a, run_program(p, {"x": x}, mode="step").outputs["o"])
