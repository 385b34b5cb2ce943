"""Spiking OS-/CA-CFAR (compiler.lowering.cfar): exactness in continuous time, step-grid
accuracy on simulated range-Doppler maps, resources from the compiled network, errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.reference import run_program, simulate
from backends.reference.continuous import simulate_continuous
from compiler.calibration import measure
from compiler.compile import compile_graph, lower_pass
from compiler.lowering.cfar import cfar_counters, cfar_op_counts
from compiler.lowering.cfar_codes import ca_linear_code, os_log_code
from compiler.passes import Verify
from compiler.passes.base import CompileContext, run_pipeline
from compiler.passes.calibrate import Calibrate
from compiler.passes.lower import Lower
from compiler.program import CompiledProgram
from ir import Graph
from ir.errors import CompileError, IRError, RadarSNNError
from ir.interpreter import evaluate
from radar.cfar import cfar, noise_estimate

#: Maps per hypothesis example (four exactness tests x examples x this >= 1 000 maps).
MAPS_PER_EXAMPLE = 4
ALPHAS = [0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0]  # dyadic: the float reference is exact on ints


def _graph(shape: dict, cfar_params: dict, domain: str = "power") -> Graph:
    return Graph.from_dict({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": shape, "domain": domain},
        {"id": "det", "op": "cfar", "input": "x", **cfar_params},
        {"id": "o", "op": "output", "input": "det"}]})


def _lower(g: Graph, **options) -> CompiledProgram:
    return run_pipeline([Verify(), lower_pass(options)], CompileContext(),
                        CompiledProgram(graph=g))


def _reference(g: Graph, maps: np.ndarray) -> np.ndarray:
    return np.array([evaluate(g, {"x": m})["det"] for m in maps])


@st.composite
def _window(draw, ndim: int):
    """(shape, guard, train, edge) with every window inside the map."""
    guard, train, shape = [], [], []
    for _ in range(ndim):
        g = draw(st.integers(0, 2 if ndim == 1 else 1))
        t = draw(st.integers(1 if ndim == 1 else 0, 3 if ndim == 1 else 2))
        guard.append(g)
        train.append(t)
        shape.append(draw(st.integers(2 * (g + t) + 1, 2 * (g + t) + 6)))
    if sum(train) == 0:
        train[0] = 1
        shape[0] = max(shape[0], 2 * (guard[0] + 1) + 1)
    edge = [draw(st.sampled_from(["clip", "wrap"])) for _ in range(ndim)]
    return shape, guard, train, edge


@st.composite
def _case(draw, ndim: int, kind: str):
    shape, guard, train, edge = draw(_window(ndim))
    axes = ["range", "doppler"][:ndim]
    n_train = int(np.prod([2 * (g + t) + 1 for g, t in zip(guard, train, strict=True)])
                  - np.prod([2 * g + 1 for g in guard]))
    params = {"kind": kind, "axes": axes, "guard": guard, "train": train, "edge": edge,
              "alpha": draw(st.sampled_from(ALPHAS))}
    if kind == "os":
        params["k"] = draw(st.integers(1, n_train))
    # small integers: ties between cells, constant regions, exact ties x_CUT = alpha * noise
    top = draw(st.integers(1, 6))
    maps = draw(st.lists(st.lists(st.integers(1, top), min_size=int(np.prod(shape)),
                                  max_size=int(np.prod(shape))),
                         min_size=MAPS_PER_EXAMPLE, max_size=MAPS_PER_EXAMPLE))
    maps = np.asarray(maps, dtype=np.float64).reshape(MAPS_PER_EXAMPLE, *shape)
    return dict(zip(axes, shape, strict=True)), params, maps


def _check_exact(shape, params, maps, **options):
    g = _graph(shape, params)
    net = _lower(g, **options).networks[0]
    spiking = simulate_continuous(net, {"x": maps}).outputs["det"] > 0
    np.testing.assert_array_equal(spiking, _reference(g, maps))


def _os_range(params, maps):
    a = params["alpha"]
    return (float(maps.min()) * min(a, 1 / a) / 2, float(maps.max()))


@pytest.mark.parametrize("ndim", [1, 2])
@given(data=st.data())
def test_os_exact_in_continuous_time(ndim, data):
    shape, params, maps = data.draw(_case(ndim, "os"))
    _check_exact(shape, params, maps, cfar_range=_os_range(params, maps), cfar_ties="exact",
                 time_steps=64)


@pytest.mark.parametrize("ndim", [1, 2])
@given(data=st.data())
def test_ca_exact_in_continuous_time(ndim, data):
    shape, params, maps = data.draw(_case(ndim, "ca"))
    # x_lo = 0, x_hi = 8 and T = 64: dyadic spike times, so every membrane sum is exact
    _check_exact(shape, params, maps, cfar_range=(0.0, 8.0), time_steps=65)


@given(data=st.data())
def test_ca_offset_code_exact_away_from_float_ties(data):
    """x_lo > 0 folds the offset into the CUT delay; exact wherever the real margin is not 0."""
    shape, params, maps = data.draw(_case(2, "ca"))
    params["alpha"] = data.draw(st.sampled_from([1.25, 1.5, 2.0, 3.0]))
    maps = maps + data.draw(st.floats(0.0, 1.0)) * np.arange(maps.size).reshape(maps.shape) / 97
    g = _graph(shape, params)
    net = _lower(g, cfar_range=(0.5, float(maps.max()) + 1.0), time_steps=50).networks[0]
    assert net.meta["cfar"]["det"]["cut_delay"] >= 0
    spiking = simulate_continuous(net, {"x": maps}).outputs["det"] > 0
    ref = _reference(g, maps)
    win = g.op("det").window("det", g.infer_types()["x"])
    est = np.array([noise_estimate(m, kind="ca", guard=list(win.guard), train=list(win.train),
                                   edge=list(win.edge)) for m in maps])
    clear = np.abs(maps - params["alpha"] * est) > 1e-9 * (1 + maps)
    np.testing.assert_array_equal(spiking[clear], ref[clear])


def test_batch_axis_and_axis_order():
    """CFAR over (range, doppler) of a [rx, doppler, range] value: rx is a batch axis."""
    rng = np.random.default_rng(3)
    x = rng.integers(1, 7, size=(3, 2, 9, 12)).astype(np.float64)
    for kind, extra in (("os", {"k": 10, "alpha": 1.5}), ("ca", {"alpha": 1.5})):
        params = {"kind": kind, "axes": ["range", "doppler"], "guard": [1, 1], "train": [2, 1],
                  "edge": ["clip", "wrap"], **extra}
        g = _graph({"rx": 2, "doppler": 9, "range": 12}, params)
        opts = ({"cfar_range": (0.25, 6.0), "cfar_ties": "exact"} if kind == "os"
                else {"cfar_range": (0.0, 8.0), "time_steps": 65})
        net = _lower(g, **opts).networks[0]
        spiking = simulate_continuous(net, {"x": x}).outputs["det"] > 0
        np.testing.assert_array_equal(spiking, _reference(g, x))


def test_hand_worked_os_neuron():
    """1D, guard 0, train 1, k = 1, alpha = 2: detect iff x > 2 * max(neighbours)."""
    x = np.array([1.0, 5.0, 2.0, 2.0, 4.0, 1.0])
    params = {"kind": "os", "guard": 0, "train": 1, "k": 1, "alpha": 2.0, "edge": "clip"}
    g = _graph({"range": 6}, params)
    net = _lower(g, cfar_range=(0.25, 8.0), cfar_ties="exact", time_steps=40).networks[0]
    # 5 > 2*max(1, 2) = 4 yes; 4 > 2*max(2, 1) = 4 no (strict); 2 > 2*5 no
    assert simulate_continuous(net, {"x": x}).outputs["det"].tolist() == [0, 1, 0, 0, 0, 0]
    assert cfar(x, kind="os", guard=0, train=1, k=1, alpha=2.0).tolist() == [
        False, True, False, False, False, False]
    step = simulate(net, {"x": x}, mode="step").outputs["det"]
    assert step.tolist() == [0, 1, 0, 0, 0, 0]


def test_hand_worked_ca_membrane():
    """CA, 1D, guard 0, train 1 (N = 2), alpha = 1.5, x_hi = 8, T = 16: v(T) = 2(2x_c - 1.5 S)."""
    x = np.array([2.0, 4.0, 2.0, 6.0])
    params = {"kind": "ca", "guard": 0, "train": 1, "alpha": 1.5, "edge": "clip"}
    g = _graph({"range": 4}, params)
    net = _lower(g, cfar_range=(0.0, 8.0), time_steps=17).networks[0]
    code = ca_linear_code(0.0, 8.0, alpha=1.5, n_steps=17)[0]
    assert code.spike_steps(x).tolist() == [12, 8, 12, 4]  # t = 16 (8 - x) / 8
    # cell 1: n=2, 2*4 - 1.5*(2+2) = 2 > 0; cell 2: 2*2 - 1.5*10 < 0; cell 3 (clip, n=1): 6 - 3 > 0
    # cell 0 (clip, n=1): 2 - 1.5*4 < 0
    assert simulate(net, {"x": x}, mode="step").outputs["det"].tolist() == [0, 1, 0, 1]
    assert cfar(x, kind="ca", guard=0, train=1, alpha=1.5).tolist() == [False, True, False, True]


def test_codes_hand_worked():
    code, d_cut, d_train, info = os_log_code(1.0, np.e ** 4, alpha=np.e, n_steps=40,
                                             ties="exact")
    # 40 steps over 4 nepers: s = 10 steps/neper, ln(alpha) = 1 neper -> D = 10 exactly
    assert (code.t_max, d_cut, d_train) == (40, 10, 0)
    assert info["steps_per_neper"] == pytest.approx(10.0)
    code, d_cut, _, info = os_log_code(1.0, np.e ** 4, alpha=np.e, n_steps=40)
    # balanced: s*ln(alpha) = D + 1/2 with D = floor(10 - 1/2) = 9 -> range widened to 4.21 nepers
    assert d_cut == 9 and info["delay_real"] == pytest.approx(9.5)
    assert code.x_min < 1.0
    code, d_cut, d_train, _ = os_log_code(1.0, 100.0, alpha=0.5, n_steps=50, ties="exact")
    assert d_cut == 0 and d_train > 0
    # CA offset: T = 10, x in [2, 12], alpha = 2: d = floor(10 * 2 * 1 / 10) = 2, x_lo = 2
    code, d = ca_linear_code(2.0, 12.0, alpha=2.0, n_steps=11)
    assert (d, code.x_min, code.t_max) == (2, 2.0, 10)


def test_closed_equals_step_on_a_compiled_cfar():
    rng = np.random.default_rng(0)
    x = rng.exponential(1.0, size=(3, 16, 12))
    for kind, extra in (("os", {"k": 20}), ("ca", {})):
        params = {"kind": kind, "guard": [1, 1], "train": [2, 2], "alpha": 3.0,
                  "edge": ["clip", "wrap"], **extra}
        g = _graph({"range": 16, "doppler": 12}, params)
        net = _lower(g, cfar_range=(0.01, 8.0), time_steps=64).networks[0]
        # the code's top is 8 on purpose: both engines clip the few larger cells alike
        a = simulate(net, {"x": x}, mode="step", out_of_range="clip").outputs["det"]
        b = simulate(net, {"x": x}, mode="closed", out_of_range="clip").outputs["det"]
        np.testing.assert_array_equal(a, b)


# ---------------------------------------------------------------- step-grid accuracy (reduced)
def _rd_maps(n: int, seed: int) -> np.ndarray:
    from benchmarks.cfar import rd_maps

    return rd_maps(n, seed=seed)


@pytest.fixture(scope="module")
def study_maps():
    return _rd_maps(6, seed=1000), _rd_maps(14, seed=1)


@pytest.mark.parametrize(("kind", "need", "quantiles"), [
    ("os", 0.99, None),            # default: the code reaches the calibration maximum
    ("os", 0.995, (0.01, 0.99)),   # a 99 % top: finer steps, but the strongest CUTs clip
    ("ca", 0.99, None)])
def test_step_accuracy_on_db_maps(study_maps, kind, need, quantiles):
    from benchmarks.cfar import ALPHA, score, study_graph

    cal, test = (10 * np.log10(m) for m in study_maps)
    program = CompiledProgram(graph=study_graph(kind, "db"))
    program.records["calibrate"] = {"rd": measure("rd", cal)}  # what Calibrate records for rd
    options = {"time_steps": 100, **({"cfar_quantiles": quantiles} if quantiles else {})}
    net = run_pipeline([Verify(), lower_pass(options)], CompileContext(), program).networks[0]
    assert net.n_steps == 100
    # calibrated on other maps (and the 99 % top on purpose): the code clips what is above
    spiking = simulate(net, {"rd": test}, mode="step", out_of_range="clip").outputs["det"] > 0
    ref = np.array([cfar(m, kind=kind, guard=[3, 3], train=[4, 4], alpha=ALPHA[kind]["db"],
                         k=132 if kind == "os" else None, edge=["clip", "wrap"]) for m in test])
    sens, prec = score(ref, spiking)
    assert ref.sum() / len(test) > 20  # a realistic detection load
    assert sens >= need and prec >= need, (sens, prec)


# ---------------------------------------------------------------- resources, Table 1
def test_resources_of_the_256x64_os_cfar():
    from benchmarks.cfar import study_graph

    g = study_graph("os", "db")
    net = _lower(g, cfar_range=(40.0, 150.0), time_steps=100).networks[0]
    c = cfar_counters(net, "det")
    assert (c["neurons"], c["inputs"], c["synapses"]) == (16_384, 16_384, 2_899_968)
    assert c["synapses_per_cut"] == 177 and c["n_train"] == 176 and c["n_steps"] == 100
    counts = cfar_op_counts("os", c["n_train"], c["n_steps"])
    assert (counts["conventional"]["total"], counts["spiking"]["total"]) == (177, 276)
    g = study_graph("ca", "db")
    net = _lower(g, cfar_range=(40.0, 150.0), time_steps=500).networks[0]
    c = cfar_counters(net, "det")
    counts = cfar_op_counts("ca", c["n_train"], c["n_steps"])
    assert (counts["conventional"]["total"], counts["spiking"]["total"]) == (177, 1176)
    assert net.n_synapses == 176 + 16_384  # one shared kernel, one diagonal


def test_mask_port_feeds_later_ops_through_run_program():
    x = np.array([1.0, 1.0, 9.0, 1.0, 1.0, 1.0])
    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 6}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "x", "kind": "ca", "guard": 0, "train": 1,
         "alpha": 2.0, "edge": "wrap"},
        {"id": "o", "op": "output", "input": "det"}]})
    ctx = CompileContext(calibration_inputs={"x": x})
    program = run_pipeline([Verify(), Calibrate(), Lower()], ctx, CompiledProgram(graph=g))
    out = run_program(program, {"x": x}).outputs["o"]
    assert out.tolist() == [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    assert program.networks[0].decoders[0].kind == "spiked"


# ---------------------------------------------------------------- errors name the node
@pytest.mark.parametrize(("params", "shape", "match"), [
    ({"kind": "os", "guard": 3, "train": 4, "k": 10, "alpha": 2.0}, {"range": 12},
     "window 2\\*\\(guard\\+train\\)\\+1 = .* = 15 is larger than axis 'range' of size 12"),
    ({"kind": "os", "guard": 1, "train": 2, "k": 5, "alpha": 2.0}, {"range": 12},
     "k=5 is outside 1..4"),
])
def test_verification_errors_name_the_node(params, shape, match):
    with pytest.raises(IRError, match=match) as err:
        compile_graph(_graph(shape, params))
    assert "'det'" in str(err.value)


def test_alpha_and_complex_errors_name_the_node():
    with pytest.raises(RadarSNNError, match="det"):
        compile_graph(_graph({"range": 12}, {"kind": "ca", "guard": 1, "train": 2,
                                             "alpha": 0.0}))
    with pytest.raises(RadarSNNError, match="'det'.*complex"):
        compile_graph(Graph.from_dict({"name": "c", "nodes": [
            {"id": "x", "op": "input", "shape": {"range": 12}, "complex": True},
            {"id": "det", "op": "cfar", "input": "x", "kind": "ca", "guard": 1, "train": 2,
             "alpha": 2.0},
            {"id": "o", "op": "output", "input": "det"}]}))


def test_missing_range_is_a_compile_error_naming_the_node():
    g = _graph({"range": 12}, {"kind": "ca", "guard": 1, "train": 2, "alpha": 2.0})
    with pytest.raises(CompileError, match="node 'det' \\(cfar\\): no calibration") as err:
        _lower(g)
    assert err.value.node == "det"


def test_spiking_magnitude_feeding_a_spiking_cfar_compiles_and_runs():
    # regression: the CFAR rule opened its builder before encoding its (spiking) input, and the
    # encode closed that network ("projection 'det/train': unknown population 'det/in'")
    from backends.reference import run_program
    from compiler.compile import compile_graph
    from ir import Graph

    g = Graph.from_dict({"name": "m", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 8, "sample": 16}, "complex": True},
        {"id": "r", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
        {"id": "mag", "op": "magnitude", "input": "r", "kind": "l1"},
        {"id": "det", "op": "cfar", "input": "mag", "kind": "os", "axes": ["range"],
         "guard": 1, "train": 3, "k": 4, "alpha": 3.0, "edge": "wrap"},
        {"id": "o", "op": "output", "input": "det"}]})
    rng = np.random.default_rng(0)
    x = rng.standard_normal((8, 16)) + 1j * rng.standard_normal((8, 16))
    for motif in ("l1", "amb"):
        program = compile_graph(g, None, calibration_inputs={"x": x}, motifs={"mag": motif})
        assert [s.kind for s in program.segments][:1] == ["spiking"]
        assert run_program(program, {"x": x}).outputs["o"].shape == (8, 16)
