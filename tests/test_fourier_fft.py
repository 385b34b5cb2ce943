"""The ``time-fft`` motif: radix-4 / mixed-radix S-FFT stages, resources, timing, accuracy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.reference import simulate
from compiler.compile import motif_settings
from compiler.lowering import LoweringContext, default_registry, lower_graph
from compiler.lowering.dft_common import op_weights, sft_rmse
from compiler.lowering.dft_fft import (
    fft_stages,
    op_stages,
    radix_plan,
    sfft_resources,
)
from ir import Graph
from ir.errors import CompileError
from ir.interpreter import evaluate
from ir.ops import DFT
from radar.loaders import load_ti_chirps


def _graph(n: int, reps: int = 1, **dft) -> Graph:
    return Graph.from_dict({"name": "fft", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": reps, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin", **dft},
        {"id": "o", "op": "output", "input": "f"}]})


def _lower(g: Graph, steps: int, calibration: dict | None = None, **options):
    ctx = LoweringContext(graph=g, registry=default_registry(), motifs={"dft": "time-fft"},
                          settings=motif_settings({"time_steps": steps, **options}),
                          calibration=calibration or {})
    return lower_graph(ctx)[0].network


def _calibration(x: np.ndarray, y: np.ndarray) -> dict:
    return {"x": {"max_re": float(np.abs(x).max()), "max_im": 0.0},
            "f": {"max_re": float(np.abs(y.real).max()), "max_im": float(np.abs(y.imag).max())}}


@given(st.sampled_from([2, 4, 6, 8, 12, 16, 24, 32, 64, 128, 256, 512]))
def test_stages_multiply_to_the_dft(n):
    stages, bins = fft_stages(n)
    prod = np.eye(n, dtype=complex)
    for a in stages:
        prod = a @ prod
    assert np.allclose(prod, np.fft.fft(np.eye(n), axis=0)[bins], atol=1e-9)
    assert sorted(bins.tolist()) == list(range(n))


@pytest.mark.parametrize("n, plan", [(512, (4, 4, 4, 4, 2)), (256, (4, 4, 4, 4)), (8, (4, 2)),
                                     (96, (4, 4, 2, 3))])
def test_radix_plan_is_radix4_then_radix2(n, plan):
    assert radix_plan(n) == plan


@pytest.mark.parametrize("dft", [{}, {"keep": "positive", "window": "hann"},
                                 {"shift": True, "n_fft": 64}, {"keep": "positive", "n_fft": 32}])
def test_op_stages_fold_window_padding_and_bins(dft):
    op = DFT(axis="sample", **dft)
    stages = op_stages(op, 24 if "n_fft" in dft else 16)
    prod = stages[0].toarray()
    for a in stages[1:]:
        prod = a @ prod
    assert np.allclose(prod, op_weights(op, stages[0].shape[1]), atol=1e-9)


def test_table3_row_from_the_estimate():
    r = sfft_resources(512, 100)
    assert (r.n_layers, r.neurons, r.synapses, r.steps) == (4.5, 4608, 37888, 550)
    with pytest.raises(CompileError, match="power of 2"):
        sfft_resources(96, 100)


@pytest.mark.parametrize("n", [256, 512])
def test_compiled_counters_against_the_estimate(n):
    net = _lower(_graph(n, reps=3), steps=100)
    est = sfft_resources(n, 100)
    layers = len(radix_plan(n))
    pops = [p for p in net.populations if not p.source and not p.id.endswith("clock")]
    assert [p.size // 3 for p in pops] == [2 * n] * layers  # 2N neurons per layer and instance
    assert net.n_steps == (layers + 1) * 100
    butterflies = [p for p in net.projections if "/w" in p.id]
    assert all(p.n_synapses <= 16 * n for p in butterflies)
    if n == 256:  # a power of 4: the structures coincide
        assert sum(p.size for p in pops) // 3 == est.neurons and net.n_steps == est.steps
        assert sum(p.n_synapses for p in butterflies) <= est.synapses
    else:  # 4.5 "layers": the radix-2 layer is a whole layer of 2N neurons and T steps
        assert sum(p.size for p in pops) // 3 == est.neurons + n
        assert net.n_steps == est.steps + 50


def test_two_point_fft_by_hand():
    # x = (0.75, 0.25), X = 1, T = 8: spikes at steps 4 - x/0.25 = 1 and 3.  Worst-case bound
    # Y = 2 so gain b = 2, v_th = 9.  Re bin 0: V = 7 + 5 - 8 (clock) = 4, fires at 8 + 3 - 1 = 10
    # -> 0.5 * (12 - 10) = 1.0; Re bin 1: V = 7 - 5 = 2 -> step 11 -> 0.5; Im: V = 0 -> step 12.
    net = _lower(_graph(2), steps=8)
    r = simulate(net, {"x": np.array([[0.75, 0.25]])}, mode="step")
    assert r.first_spike_steps["f/out"].reshape(2, 2).tolist() == [[10, 12], [11, 12]]
    assert r.outputs["f"].tolist() == [[1.0 + 0j, 0.5 + 0j]]


def test_closed_equals_step_on_the_sfft():
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, (4, 64))
    net = _lower(_graph(64, reps=4, keep="positive", window="hann"), steps=64)
    step, closed = (simulate(net, {"x": x}, mode=m) for m in ("step", "closed"))
    assert closed.mode == "closed"
    for pid, first in step.first_spike_steps.items():
        assert np.array_equal(first, closed.first_spike_steps[pid]), pid
    assert np.array_equal(step.outputs["f"], closed.outputs["f"])


def test_odd_time_steps_are_refused():
    with pytest.raises(CompileError, match="even"):
        _lower(_graph(8), steps=9)


@pytest.mark.parametrize("n", [256, 1024])
def test_sfft_within_1_5x_of_the_dense_sft_on_ti_chirps(shared_data, n):
    x = load_ti_chirps(shared_data)[0][:, :n]
    g = _graph(n, reps=4)
    ref = evaluate(g, {"x": x})["f"]
    cal = _calibration(x, ref)
    fft = simulate(_lower(g, 256, cal), {"x": x}, mode="closed").outputs["f"]
    dense = simulate(_lower(g, 256, cal, fft_radices=[n]), {"x": x}, mode="closed").outputs["f"]
    e_fft, e_dense = sft_rmse(fft, ref), sft_rmse(dense, ref)
    assert e_fft <= 1.5 * e_dense, (e_fft, e_dense)
    assert e_fft < 0.03
