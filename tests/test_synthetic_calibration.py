"""Synthetic calibration inputs (``radarsnn compile/report/emit`` without ``--calibration``)
are drawn in each input's domain, so chains whose input is a power, a dB level or a mask
compile; a domain without a generator is a CompileError that says to pass calibration."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from compiler.calibration import SYNTHETIC, synthetic_inputs
from ir import Graph, evaluate
from ir.errors import CompileError
from radarsnn.cli import main
from radarsnn.cli.emit import run_emit

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _chain(domain: str, tail: list[dict]) -> Graph:
    return Graph.from_dict({"name": f"{domain}-chain", "nodes": [
        {"id": "rd", "op": "input", "shape": {"range": 16, "doppler": 4}, "domain": domain},
        *tail, {"id": "out", "op": "output", "input": tail[-1]["id"] if tail else "rd"}]})


CFAR = {"id": "det", "op": "cfar", "input": "rd", "kind": "ca", "axes": ["range"], "guard": 1,
        "train": 2, "alpha": 3.0}
CHAINS = {
    "power": _chain("power", [CFAR]),
    "db": _chain("db", [CFAR]),
    "power-log": _chain("power", [{"id": "lvl", "op": "log", "input": "rd"},
                                  {**CFAR, "input": "lvl"}]),
    "mask": _chain("mask", []),
}


@given(st.integers(0, 2**32 - 1))
def test_each_domain_draws_values_of_its_kind(seed):
    g = Graph.from_dict({"name": "all", "nodes": [
        {"id": "adc", "op": "adc_input", "shape": {"chirp": 3, "sample": 8}, "complex": True},
        {"id": "a", "op": "input", "shape": {"n": 64}},
        {"id": "p", "op": "input", "shape": {"n": 64}, "domain": "power"},
        {"id": "d", "op": "input", "shape": {"n": 64}, "domain": "db"},
        {"id": "m", "op": "input", "shape": {"n": 64}, "domain": "mask"},
        *({"id": f"o_{k}", "op": "output", "input": k} for k in ("adc", "a", "p", "d", "m"))]})
    x = synthetic_inputs(g, seed=seed)
    assert x["adc"].shape == (3, 8) and x["adc"].dtype == np.complex128
    assert x["a"].dtype == np.float64 and (x["a"] < 0).any()  # P(no negative) = 2**-64
    assert x["p"].dtype == np.float64 and (x["p"] >= 0).all()
    assert np.isfinite(x["d"]).all() and x["d"].min() >= -300
    assert x["m"].dtype == np.bool_
    evaluate(g, x)  # every array passes the interpreter's input checks (power >= 0, bool masks)
    again = synthetic_inputs(g, seed=seed)
    for k in x:
        np.testing.assert_array_equal(again[k], x[k])


def test_draws_hand_checked():
    """Amplitude draws are unchanged (the same stream as before domains mattered); power is
    Exp(1) = |z|² of unit complex noise; dB is 10·log10 of it: mean -10γ/ln 10 ≈ -2.51 dB,
    standard deviation (10/ln 10)·π/√6 ≈ 5.57 dB."""
    g = Graph.from_dict({"name": "s", "nodes": [
        {"id": "a", "op": "input", "shape": {"n": 4}, "complex": True},
        {"id": "o", "op": "output", "input": "a"}]})
    rng = np.random.default_rng(5)
    re, im = rng.standard_normal(4), rng.standard_normal(4)
    np.testing.assert_array_equal(synthetic_inputs(g, seed=5)["a"], (re + 1j * im) / np.sqrt(2))
    big = (200_000,)
    p = SYNTHETIC["power"](np.random.default_rng(1), big, False)
    assert p.mean() == pytest.approx(1.0, abs=0.01)
    d = SYNTHETIC["db"](np.random.default_rng(1), big, False)
    np.testing.assert_array_equal(d, 10 * np.log10(p))
    assert d.mean() == pytest.approx(-10 * np.euler_gamma / np.log(10), abs=0.05)
    assert d.std() == pytest.approx(10 / np.log(10) * np.pi / np.sqrt(6), abs=0.05)


def test_a_domain_without_a_generator_names_the_node_and_the_way_out():
    with pytest.raises(CompileError, match=r"input 'rd': no synthetic calibration for domain "
                                           r"'power' .*--calibration") as info:
        synthetic_inputs(CHAINS["power"], generators={"amplitude": SYNTHETIC["amplitude"]})
    assert info.value.node == "rd"


@pytest.mark.parametrize("name", sorted(CHAINS))
def test_compile_report_and_emit_without_calibration(name, tmp_path, capsys):
    chain = tmp_path / f"{name}.yaml"
    chain.write_text(CHAINS[name].to_yaml())
    assert main(["compile", str(chain), "-o", str(tmp_path / "art"), "-q"]) == 0
    capsys.readouterr()
    assert main(["report", str(chain), "-q"]) == 0
    assert "calibrated on synthetic noise" in capsys.readouterr().out
    package = run_emit(chain, tmp_path / "emitted")
    assert (package / "program.py").is_file()


def test_the_db_sweep_chain_reports_without_calibration(capsys):
    assert main(["report", str(EXAMPLES / "sweeps" / "os_cfar_db.yaml"), "-q"]) == 0
    assert "synthetic noise" in capsys.readouterr().out


def test_synthetic_inputs_refuse_an_input_too_large_to_draw():
    from ir import Graph
    from ir.errors import BudgetError

    def chain(n: int) -> Graph:
        return Graph.from_dict({"nodes": [{"id": "x", "op": "input", "shape": {"a": n}},
                                          {"id": "o", "op": "output", "input": "x"}]})

    with pytest.raises(BudgetError, match=r"node 'x' \(input\) is a \{'a': 4611686018427387904\} "
                                          "value of 3.7e.19 bytes, more than any array") as info:
        synthetic_inputs(chain(2**62), seed=0)  # numpy's "array is too big" ValueError before
    assert info.value.node == "x"
    with pytest.raises(BudgetError, match=r"drawing synthetic calibration inputs needs 8\.8e\+12 "
                                          r"bytes for the values \(over max_memory_bytes="):
        synthetic_inputs(chain(2**40), seed=0)  # an 8.8 TB MemoryError before
