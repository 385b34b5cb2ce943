"""The reference interpreter against hand-written numpy pipelines and hand-worked numbers."""

from __future__ import annotations

import copy
import itertools
import math
from pathlib import Path
from typing import Literal

import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from ir import (
    CFAR,
    EVAL_REGISTRY,
    OP_REGISTRY,
    Graph,
    IRError,
    Op,
    RadarConfigError,
    TensorType,
    evaluate,
)

CHAINS = Path(__file__).resolve().parents[1] / "examples" / "chains"


def _load(name: str, **shape: int) -> Graph:
    """An example chain, with its input node's shape entries replaced (to keep tests small)."""
    data = yaml.safe_load((CHAINS / name).read_text())
    data["nodes"][0]["shape"].update(shape)
    return Graph.from_dict(data)


def _one(*nodes: dict, shape: dict, **src: object) -> Graph:
    """``x`` (an input) -> nodes ... -> ``out``; node ids are ``n0, n1, ...``."""
    listed = [{"id": "x", "op": "input", "shape": shape, **src}]
    for i, node in enumerate(nodes):
        listed.append({"id": f"n{i}", "input": listed[-1]["id"], **node})
    listed.append({"id": "out", "op": "output", "input": listed[-1]["id"]})
    return Graph.from_dict({"name": "t", "nodes": listed})


def cfar_reference(x: np.ndarray, kind: str, guard: list, train: list, alpha: float,
                   k: int | None, edge: list) -> np.ndarray:
    """Independent CFAR over all axes of ``x``, cell by cell (slow, obvious).

    Training offsets: inside the window, outside the guard block. ``wrap`` reads
    cells periodically; ``clip`` drops cells outside the map, and OS then takes the
    ``ceil(k * n / N)``-th largest (at least 1) of the ``n`` cells left.
    """
    spans = [range(-(g + t), g + t + 1) for g, t in zip(guard, train, strict=True)]
    offsets = [o for o in itertools.product(*spans)
               if any(abs(oi) > g for oi, g in zip(o, guard, strict=True))]
    det = np.zeros(x.shape, dtype=bool)
    for cell in np.ndindex(x.shape):
        vals = []
        for off in offsets:
            pos = [c + o for c, o in zip(cell, off, strict=True)]
            pos = [p % n if e == "wrap" else p for p, n, e in zip(pos, x.shape, edge, strict=True)]
            if all(0 <= p < n for p, n in zip(pos, x.shape, strict=True)):
                vals.append(x[tuple(pos)])
        if kind == "ca":
            noise = sum(vals) / len(vals)
        else:
            k_eff = min(max(math.ceil(k * len(vals) / len(offsets)), 1), len(vals))
            noise = sorted(vals, reverse=True)[k_eff - 1]
        det[cell] = x[cell] > alpha * noise
    return det


def _close(a: np.ndarray, b: np.ndarray) -> None:
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * float(np.abs(b).max() + 1))


# -- the example chains vs hand-written numpy -----------------------------------------------


def test_carrada_chain_small_equals_numpy_pipeline() -> None:
    g = _load("carrada_rd_oscfar.yaml", rx=2, chirp=16, sample=32)
    rng = np.random.default_rng(1)
    adc = rng.standard_normal((2, 16, 32)) + 1j * rng.standard_normal((2, 16, 32))
    adc[:, :, :] += 3 * np.exp(2j * np.pi * (5 * np.arange(32) / 32 + 3 * np.arange(16)[:, None]
                                             / 16))  # a target: range bin 5, Doppler bin 3
    v = evaluate(g, {"adc": adc})

    win = adc * np.hanning(32)  # symmetric Hann
    rng_ = np.fft.fft(win, axis=2)
    dop = np.fft.fftshift(np.fft.fft(rng_, axis=1), axes=1)
    rd = np.abs(dop).sum(axis=0)  # [doppler, range]
    det = cfar_reference(rd.T, "os", [3, 3], [4, 4], 1.2, 132, ["clip", "wrap"]).T
    for node, expected in [("win", win), ("rng", rng_), ("dop", dop), ("rd", rd)]:
        _close(v[node], expected)
    np.testing.assert_array_equal(v["out"], det)
    assert v["out"][8 + 3, 5]  # the target: zero Doppler at row 8 after the shift
    assert set(v) == set(g)


def test_seed003_chain_small_equals_numpy_pipeline() -> None:
    g = _load("seed003_range_doppler.yaml", chirp=16, sample=64)
    adc = np.random.default_rng(2).standard_normal((1, 16, 64))
    v = evaluate(g, {"adc": adc})
    spec = np.fft.fft(adc * np.hanning(64), axis=2)[:, :, :32]
    dop = np.fft.fftshift(np.fft.fft(spec, axis=1), axes=1)
    rd = (np.abs(dop) ** 2).sum(axis=0)
    n = 13 * 21 - 5 * 5  # window (2(2+4)+1) x (2(2+8)+1) minus the 5 x 5 guard block
    alpha = n * (1e-4 ** (-1 / n) - 1)  # CA-CFAR: Pfa = (1 + alpha/N)^-N
    _close(v["rd"], rd)
    np.testing.assert_array_equal(
        v["out"], cfar_reference(rd, "ca", [2, 2], [4, 8], alpha, None, ["wrap", "clip"]))
    assert g.op("det").alpha_for(n) == pytest.approx(alpha, rel=1e-12)


def test_ti_range_chain_equals_numpy_pipeline() -> None:
    g = _load("ti_range.yaml")
    x = np.random.default_rng(3).standard_normal(1024)
    v = evaluate(g, {"chirp": x})
    mag = np.abs(np.fft.fft(x)[:512])
    _close(v["mag"], mag)
    np.testing.assert_array_equal(
        v["out"], cfar_reference(mag, "os", [2], [12], 6.0, 18, ["clip"]))


def test_carrada_full_size_matches_numpy_and_radar_cfar() -> None:
    from radar.cfar import cfar

    g = Graph.from_yaml(CHAINS / "carrada_rd_oscfar.yaml")
    rng = np.random.default_rng(4)
    adc = rng.standard_normal((4, 64, 256)) + 1j * rng.standard_normal((4, 64, 256))
    v = evaluate(g, {"adc": adc})
    dop = np.fft.fftshift(np.fft.fft(np.fft.fft(adc * np.hanning(256), axis=2), axis=1), axes=1)
    rd = np.abs(dop).sum(axis=0)
    _close(v["rd"], rd)
    expected = cfar(rd.T, kind="os", guard=[3, 3], train=[4, 4], k=132, alpha=1.2,
                    edge=["clip", "wrap"]).T
    np.testing.assert_array_equal(v["det"], expected)


def test_ti_range_on_real_chirps(shared_data: Path) -> None:
    """The TI captures: range spectrum equals the stored FFT; annotated targets are detected."""
    chirps = np.load(shared_data / "ti_chirps" / "data_tum.npy", allow_pickle=False)
    fft = np.load(shared_data / "ti_chirps" / "fft_result.npy", allow_pickle=False)
    g = Graph.from_yaml(CHAINS / "ti_range.yaml")
    annotated = {0: [25, 201], 2: [42, 66], 3: [1, 39, 87, 127]}  # data README; 1: too weak
    for i, chirp in enumerate(chirps):
        v = evaluate(g, {"chirp": chirp.astype(np.float64)})
        ref = fft[i, :512].astype(np.complex128)
        np.testing.assert_allclose(v["rng"], ref, atol=1e-6 * np.abs(ref).max())  # complex64
        hits = np.flatnonzero(v["out"])
        for b in annotated.get(i, []):
            assert np.abs(hits - b).min() <= 1, (i, b, hits)


# -- hand-worked single ops -----------------------------------------------------------------


def test_dft_zero_padding_keep_and_shift_hand_worked() -> None:
    x = np.array([1.0, 2.0, 3.0])
    # X[k] = 1 + 2 e^{-i pi k/2} + 3 e^{-i pi k}: [6, -2-2i, 2, -2+2i]
    full = [6, -2 - 2j, 2, -2 + 2j]
    cases = [({}, full), ({"keep": "positive"}, full[:2]), ({"shift": True}, full[2:] + full[:2])]
    for params, expected in cases:
        g = _one({"op": "dft", "axis": "s", "n_fft": 4, **params}, shape={"s": 3})
        np.testing.assert_allclose(evaluate(g, {"x": x})["out"], expected, atol=1e-12)


def test_window_magnitude_log_threshold_hand_worked() -> None:
    g = _one({"op": "window", "axis": "s", "kind": "hann"}, shape={"s": 5})
    assert evaluate(g, {"x": np.ones(5)})["out"].tolist() == pytest.approx([0, .5, 1, .5, 0])
    for kind, expected in [("l2", 5.0), ("l1", 7.0), ("square", 25.0)]:
        g = _one({"op": "magnitude", "kind": kind}, shape={"s": 1}, complex=True)
        assert evaluate(g, {"x": np.array([3 - 4j])})["out"].tolist() == [expected]
    g = _one({"op": "log"}, shape={"s": 3})
    assert evaluate(g, {"x": np.array([10.0, 1.0, 0.0])})["out"].tolist() == [20.0, 0.0, -300.0]
    g = _one({"op": "log", "floor_db": -40.0}, shape={"s": 2}, domain="power")
    assert evaluate(g, {"x": np.array([100.0, 1e-6])})["out"].tolist() == [20.0, -40.0]
    for strict, expected in [(True, [False, False, True]), (False, [False, True, True])]:
        g = _one({"op": "threshold", "value": 2.0, "strict": strict}, shape={"s": 3}, domain="db")
        assert evaluate(g, {"x": np.array([1.0, 2.0, 3.0])})["out"].tolist() == expected


def test_linear_and_sum_hand_worked() -> None:
    x = np.array([[1.0, 2.0, 3.0], [10.0, 20.0, 30.0]])  # [rx, range]
    g = _one({"op": "linear", "axis": "rx", "out_axis": "beam", "matrix": [[1, 1], [1, -1]],
              "matrix_imag": [[0, 1], [0, 0]]}, {"op": "sum", "axis": "range"},
             shape={"rx": 2, "range": 3})
    v = evaluate(g, {"x": x})
    np.testing.assert_array_equal(v["n0"], [[11 + 10j, 22 + 20j, 33 + 30j], [-9, -18, -27]])
    np.testing.assert_array_equal(v["out"], [66 + 60j, -54])


def test_cfar_hand_worked_and_batched_over_other_axes() -> None:
    row = [1.0, 1.0, 1.0, 8.0, 1.0, 1.0, 2.0]
    # cell 3: training cells 0, 1, 5, 6 -> mean 1.25 -> 8 > 4 * 1.25; cell 6 (clip): cells 3, 4
    # -> mean 4.5 -> 2 < 18
    g = _one({"op": "cfar", "kind": "ca", "guard": 1, "train": 2, "alpha": 4.0},
             shape={"s": 7})
    assert np.flatnonzero(evaluate(g, {"x": np.array(row)})["out"]).tolist() == [3]
    # a batch axis before and after: each line along 'col' is an independent 1D CFAR
    x = np.random.default_rng(5).exponential(size=(3, 9, 2))
    g = _one({"op": "cfar", "kind": "os", "axes": ["col"], "guard": 1, "train": 2, "k": 3,
              "alpha": 1.5, "edge": "wrap"}, shape={"a": 3, "col": 9, "b": 2}, domain="power")
    out = evaluate(g, {"x": x})["out"]
    for i, j in np.ndindex(3, 2):
        np.testing.assert_array_equal(
            out[i, :, j], cfar_reference(x[i, :, j], "os", [1], [2], 1.5, 3, ["wrap"]))


def test_cfar_pfa_alphas_match_the_theory_figures() -> None:
    # NOTES.md: N=16, Pfa=1e-3 -> CA alpha 8.6388; OS 12th smallest (5th largest) -> 7.4215
    ca = CFAR(kind="ca", guard=0, train=8, pfa=1e-3)
    os_ = CFAR(kind="os", guard=0, train=8, k=5, pfa=1e-3)
    assert ca.alpha_for(16) == pytest.approx(8.6388, abs=1e-4)
    assert os_.alpha_for(16) == pytest.approx(7.4214, abs=1e-4)


@given(st.integers(0, 1), st.integers(1, 4), st.data())
def test_linear_equals_einsum(axis: int, n_out: int, data: st.DataObject) -> None:
    shape = {"a": 3, "b": 4}
    n_in = list(shape.values())[axis]
    entries = st.lists(st.lists(st.floats(-5, 5), min_size=n_in, max_size=n_in),
                       min_size=n_out, max_size=n_out)
    re_, im = data.draw(entries), data.draw(entries)
    name = list(shape)[axis]
    g = _one({"op": "linear", "axis": name, "matrix": re_, "matrix_imag": im}, shape=shape)
    x = np.arange(12.0).reshape(3, 4)
    m = np.array(re_) + 1j * np.array(im)
    expected = np.einsum("oi,ib->ob", m, x) if axis == 0 else np.einsum("oi,ai->ao", m, x)
    np.testing.assert_allclose(evaluate(g, {"x": x})["out"], expected, atol=1e-12)


# -- input checks ---------------------------------------------------------------------------

REAL = _one({"op": "magnitude"}, shape={"chirp": 2, "sample": 3})


@pytest.mark.parametrize(
    ("graph", "arrays", "match"),
    [
        (REAL, {}, r"missing input array\(s\) for \['x'\]"),
        (REAL, {"x": np.zeros((2, 3)), "n0": np.zeros(3)},
         r"got arrays for \['n0'\] which are not graph inputs \(inputs: \['x'\]\)"),
        (REAL, {"x": np.zeros((3, 2))},
         r"input 'x': array shape \(3, 2\) does not match the declared axes "
         r"\{'chirp': 2, 'sample': 3\}, shape \(2, 3\)"),
        (REAL, {"x": np.zeros((2, 3), complex)}, r"input 'x': declared real but the array is "
                                                 r"complex128"),
        (_one({"op": "magnitude"}, shape={"s": 2}, complex=True), {"x": np.zeros(2)},
         r"input 'x': declared complex but the array is float64"),
        (REAL, {"x": [[0, np.nan, 0], [np.inf, 0, 0]]},
         r"input 'x': 2 non-finite value\(s\) \(NaN/Inf\) of 6, first at index \(0, 1\)"),
        (REAL, {"x": [["a", "b", "c"], ["d", "e", "f"]]}, r"input 'x': needs a numeric array"),
        (REAL, {"x": np.ones((2, 3), bool)}, r"input 'x': needs a numeric array; got dtype bool"),
        (_one({"op": "threshold", "value": 1.0}, shape={"s": 2}, domain="power"),
         {"x": [1.0, -0.5]}, r"input 'x': a power input must be >= 0; minimum is -0\.5"),
        (_one({"op": "threshold", "value": 1.0}, shape={"s": 2}, domain="db"),
         {"x": [1.0, -0.5]}, None),
        (_one(shape={"s": 2}, domain="mask"), {"x": [1, 0]},
         r"input 'x': a mask input needs a bool array; got int64"),
    ],
)
def test_input_checks(graph: Graph, arrays: dict, match: str | None) -> None:
    if match is None:
        evaluate(graph, arrays)
        return
    with pytest.raises(IRError, match=match) as info:
        evaluate(graph, arrays)
    assert info.value.node in {"x", "n0"}


def test_inputs_are_copied_and_values_typed() -> None:
    x = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    v = evaluate(REAL, {"x": x})
    x[0, 0] = 100.0
    assert v["x"][0, 0] == 1.0 and v["out"][0, 0] == 1.0
    assert v["out"].dtype == np.float64
    assert evaluate(REAL, {"x": x.astype(np.int32)})["x"].dtype == np.float64


def test_graph_errors_surface_before_evaluation() -> None:
    bad = copy.deepcopy(REAL.to_dict())
    bad["nodes"][1]["input"] = "nope"
    with pytest.raises(IRError, match=r"node 'n0' \(magnitude\): unknown input id 'nope'"):
        evaluate(Graph.from_dict(bad), {"x": np.zeros((2, 3))})


def test_classifier_evaluation_is_an_honest_irerror() -> None:
    g = _one({"op": "classifier", "num_classes": 3, "weights": "w.npz"}, shape={"a": 2, "b": 2})
    g.verify()
    with pytest.raises(IRError, match=r"node 'n0' \(classifier\): classifier evaluation is not "
                                      r"implemented yet") as info:
        evaluate(g, {"x": np.zeros((2, 2))})
    assert info.value.node == "n0"


# -- extending the registries ---------------------------------------------------------------


class Scale(Op):
    """Test-only op: ``y = factor * x``.

    Examples
    --------
    >>> Scale(factor=2.0).op
    'scale'
    """

    op: Literal["scale"] = "scale"
    factor: float

    def infer(self, node_id: str, inputs: list[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        return t


SCALE_CHAIN = {"nodes": [{"id": "x", "op": "input", "shape": {"s": 3}},
                         {"id": "sc", "op": "scale", "input": "x", "factor": 2.5},
                         {"id": "out", "op": "output", "input": "sc"}]}


def test_custom_ops_through_explicit_registries() -> None:
    g = Graph.from_dict(SCALE_CHAIN, registry={**OP_REGISTRY, "scale": Scale})
    x = {"x": np.array([1.0, 2.0, 4.0])}

    def scale(node_id: str, op: Scale, args: list, types: list) -> np.ndarray:
        return op.factor * args[0]

    assert evaluate(g, x, registry={Scale: scale})["out"].tolist() == [2.5, 5.0, 10.0]
    assert Scale not in EVAL_REGISTRY
    with pytest.raises(IRError, match=r"node 'sc' \(scale\): no implementation for Scale"):
        evaluate(g, x)
    with pytest.raises(IRError, match=r"node 'sc' \(scale\): the implementation returned a "
                                      r"float64 array of shape \(2,\)"):
        evaluate(g, x, registry={Scale: lambda node_id, op, args, types: args[0][:2]})

    def fails(node_id: str, op: Scale, args: list, types: list) -> np.ndarray:
        raise RadarConfigError("factor too large")

    with pytest.raises(IRError, match=r"node 'sc' \(scale\): factor too large") as info:
        evaluate(g, x, registry={Scale: fails})
    assert isinstance(info.value.__cause__, RadarConfigError)
    with pytest.raises(IRError, match="unknown op 'scale'"):
        Graph.from_dict(SCALE_CHAIN)


def _huge_dft_chain(n_fft: int = 2**63) -> Graph:
    return Graph.from_dict({"nodes": [
        {"id": "x", "op": "input", "shape": {"a": 4}},
        {"id": "f", "op": "dft", "input": "x", "axis": "a", "n_fft": n_fft},
        {"id": "o", "op": "output", "input": "f"}]})


def test_evaluate_refuses_values_over_its_limit_from_the_types_before_numpy():
    from ir.errors import IRError

    impossible = (r"graph 'chain': node 'f' \(dft\) is a \{'a': 9223372036854775808\} value of "
                  r"1\.5e\+20 bytes, more than any array can hold")
    with pytest.raises(IRError, match=impossible) as info:
        evaluate(_huge_dft_chain(), {"x": np.ones(4)})  # numpy's "Maximum allowed dimension"
    assert info.value.node == "f"
    with pytest.raises(IRError, match=impossible):
        evaluate(_huge_dft_chain(), {"x": np.ones(4)}, max_memory_bytes=None)
    with pytest.raises(IRError, match=r"graph 'chain': evaluating needs 2\.2e\+12 bytes for "
                                      r"the values .*the largest is node 'f' \(dft\)"):
        evaluate(_huge_dft_chain(2**36), {"x": np.ones(4)})  # a 1 TB MemoryError before
    small = Graph.from_dict({"nodes": [{"id": "x", "op": "input", "shape": {"a": 4}},
                                       {"id": "o", "op": "output", "input": "x"}]})
    assert evaluate(small, {"x": np.ones(4)}, max_memory_bytes=64)["o"].shape == (4,)
    with pytest.raises(IRError, match="over max_memory_bytes=63"):
        evaluate(small, {"x": np.ones(4)}, max_memory_bytes=63)


def test_compile_and_run_program_refuse_values_no_array_can_hold():
    from backends.reference import run_program
    from compiler.compile import compile_graph
    from ir.errors import BudgetError, SimulationError

    with pytest.raises(BudgetError, match=r"node 'f' \(dft\) is a .* more than any array"):
        compile_graph(_huge_dft_chain(), target=None, options={  # OverflowError before
            "max_memory_bytes": None, "max_time_s": None, "input_bounds": {"x": 1.0}})
    host = Graph.from_dict({"name": "h", "nodes": [
        {"id": "x", "op": "input", "shape": {"a": 4}, "domain": "power"},
        {"id": "t", "op": "threshold", "input": "x", "value": 1.0},
        {"id": "o", "op": "output", "input": "t"}]})
    program = compile_graph(host, target=None)
    with pytest.raises(SimulationError, match="running the program needs 40 bytes"):
        run_program(program, {"x": np.ones(4)}, max_memory_bytes=39)
