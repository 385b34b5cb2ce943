"""Quantize: hand-worked scales and errors, relay chains exactly equivalent, clear errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.reference import simulate
from compiler.hardware import HardwareProfile, load_profile
from compiler.hardware.reference_networks import os_cfar_network
from compiler.passes.quantize import quantize
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import BudgetError

CODE = LatencyCode(t_max=10, x_min=0.0, x_max=1.0)


def small(weights, v_th=0.5, delays=None, stencil=False) -> SpikingNetwork:
    origin = {"node": "n", "motif": "m"}
    if stencil:
        proj = StencilProjection(id="w", source="x", target="y", axes=("i",), kernel=weights,
                                 edge=("clip",), delays=delays, origin=origin)
        shapes = ({"i": 4}, {"i": 4})
    else:
        proj = MatrixProjection(id="w", source="x", target="y", contract=("i",),
                                produce=("o",), weights=weights, delays=delays, origin=origin)
        shapes = ({"i": weights.shape[0]}, {"o": weights.shape[1]})
    return SpikingNetwork(name="s", n_steps=30, populations=[
        Population(id="x", shape=shapes[0], source=True),
        Population(id="y", shape=shapes[1], params=NeuronParams(v_th=v_th), origin=origin)],
        projections=[proj], encoders=[Encoder(port="x", population="x", code=CODE)]).validate()


def test_hand_worked_scale_and_errors():
    net = small(np.array([[1.0, 0.0], [-0.3, 0.25]]))
    q, rec = quantize(net, load_profile("loihi"))
    # scale = 1/127: 1 -> 127, -0.3 -> -38.1 -> -38, 0.25 -> 31.75 -> 32; v_th 0.5 -> 63.5 -> 64
    assert q.projection["w"].weights.tolist() == [[127.0, 0.0], [-38.0, 32.0]]
    assert q.population["y"].params.v_th == 64.0
    r = rec.projections["w"]
    assert r["scale"] == pytest.approx(1 / 127)
    assert r["max_abs_error"] == pytest.approx(abs(32 / 127 - 0.25))   # 0.00197
    assert r["mean_abs_error"] == pytest.approx((0 + abs(-38 / 127 + 0.3) + abs(32 / 127 - 0.25))
                                                / 3)
    assert rec.populations["y"]["threshold_error"] == pytest.approx(abs(64 / 127 - 0.5))
    assert q.population["y"].params.is_integer()


def test_unbounded_changes_nothing():
    net = small(np.array([[0.3]]))
    q, rec = quantize(net, "unbounded")
    assert q.projection["w"].weights.tolist() == [[0.3]] and rec.projections == {}


def test_threshold_beyond_its_range_coarsens_the_weights():
    # loihi thresholds: a 17-bit vth in 64-LSB state units, at most 131 071.  v_th = 400 at
    # weight 0.3: the unit grows from 0.3/127 to 400/131070.5, the weight 0.3 -> 98
    net, rec = quantize(small(np.array([[0.3]]), v_th=400.0), load_profile("loihi"))
    info = rec.populations[net.populations[1].id]
    assert info["weights_coarsened_for_threshold"] and not info["exact"]
    assert net.populations[1].params.v_th <= load_profile("loihi").number_format.threshold_max
    assert net.projections[0].weights[0, 0] == 98.0  # rint(0.3 / (400 / 131070.5))


def test_whole_weights_and_thresholds_stay_exact_on_loihi():
    # weight 1, v_th = 1e4: within Loihi's 17-bit vth (64-LSB state units), stored as it is
    net, rec = quantize(small(np.array([[1.0]]), v_th=1e4), load_profile("loihi"))
    assert rec.populations["y"]["exact"] and rec.projections["w"]["max_abs_error"] == 0
    assert net.projections[0].weights[0, 0] == 1.0 and net.populations[1].params.v_th == 1e4


def test_threshold_that_leaves_no_weight_names_the_node():
    with pytest.raises(BudgetError, match=r"node 'n' \(motif m.*loihi's threshold range.*"
                       r"rounds to zero"):
        quantize(small(np.array([[0.3]]), v_th=1e9), load_profile("loihi"))


def test_long_delay_error_mode():
    net = small(np.array([[1.0]]), delays=np.array([[70]]))
    with pytest.raises(BudgetError, match=r"node 'n'.*delay of 70 steps.*at most 63 \(6 delay "
                       r"bits\).*long_delays='relay'"):
        quantize(net, load_profile("loihi"))


@given(st.lists(st.integers(0, 12), min_size=6, max_size=6), st.integers(1, 3),
       st.lists(st.floats(0, 1), min_size=3, max_size=3))
def test_relay_chains_deliver_every_spike_at_the_same_step(delays, bits, x):
    # 3 inputs -> 2 IF neurons, per-synapse delays up to 12 with 1..3 delay bits (max 1..7)
    w = np.array([[0.6, 0.5], [0.4, -0.3], [0.5, 0.7]])
    net = small(w, v_th=0.5, delays=np.array(delays).reshape(3, 2))
    prof = HardwareProfile(name="d", delay_bits=bits)
    relayed, rec = quantize(net, prof, long_delays="relay")
    relayed.validate()
    assert all(p.max_delay <= prof.number_format.max_delay_steps for p in relayed.projections)
    a = simulate(net, {"x": np.array(x)})
    b = simulate(relayed, {"x": np.array(x)})
    np.testing.assert_array_equal(a.first_spike_steps["y"], b.first_spike_steps["y"])
    assert a.spike_counts["y"] == b.spike_counts["y"]


def test_relay_for_stencil_taps():
    net = small(np.array([0.3, 0.0, 0.6]), v_th=0.5, delays=np.array([9, 0, 2]), stencil=True)
    relayed, rec = quantize(net, HardwareProfile(name="d", delay_bits=2), long_delays="relay")
    assert rec.relays == ["x__relay1", "x__relay2"]  # 9 = 3 (relay 1) + 3 (relay 2) + 3
    x = np.array([0.9, 0.1, 0.5, 0.7])
    a, b = simulate(net, {"x": x}), simulate(relayed.validate(), {"x": x})
    np.testing.assert_array_equal(a.first_spike_steps["y"], b.first_spike_steps["y"])


def test_quantized_cfar_runs_in_integer_arithmetic_with_the_same_spikes():
    net = os_cfar_network(16, 32, k=40)
    q, rec = quantize(net, load_profile("loihi"))
    # one kernel: training -1, CUT k = 40, threshold 1 — whole numbers, stored as they are
    # (the old single 8-bit scale of a k + 1/2 kernel made them -3 and 127: rank 42, not 40)
    assert sorted(np.unique(q.projections[0].kernel).tolist()) == [-1.0, 0.0, 40.0]
    assert rec.populations["det"]["exact"] and rec.populations["det"]["scale"] == 1.0
    x = np.random.default_rng(0).random((2, 16, 32))
    ref = simulate(net, {"det_in": x})
    f = simulate(q, {"det_in": x}, arithmetic="float64")
    i = simulate(q, {"det_in": x}, arithmetic="int64")
    np.testing.assert_array_equal(f.first_spike_steps["det"], i.first_spike_steps["det"])
    np.testing.assert_array_equal(ref.outputs["det"], i.outputs["det"])


def test_a_half_margin_cut_weight_stays_exact_in_half_units():
    # k + 1/2 with training -1 and threshold 1: whole in units of 1/2 (-2, 81, 2)
    net = small(np.array([-1.0, 40.5, -1.0]), v_th=1.0, stencil=True)
    q, rec = quantize(net, load_profile("loihi"))
    assert q.projections[0].kernel.tolist() == [-2.0, 81.0, -2.0]
    assert rec.populations["y"]["scale"] == 0.5 and q.populations[1].params.v_th == 2.0


def test_whole_weights_beyond_one_exponent_are_split_exactly():
    # one exponent per projection: 2, 4, ..., 78 and 255 need exponent 1 (255 > 127); 255 =
    # 127·2 + 1 leaves a residual 1 at exponent 0 — one extra stored weight of 40 (2.5 %)
    w = np.concatenate([2.0 * np.arange(1, 40), [255.0]])[:, None]
    net = small(w, v_th=2.0)
    prof = HardwareProfile(name="c", weight_bits=8, weight_exponent_max=7, threshold_bits=24)
    q, rec = quantize(net, prof)
    r = rec.projections["w"]
    assert r["exact"] and r["max_abs_error"] == 0 and r["extra_weights"] == 1
    assert [t["exponent"] for t in r["terms"]] == [1, 0]
    assert sum(p.weights for p in q.projections).tolist() == w.tolist()
    assert [p.id for p in q.projections] == ["w", "w__x1"]
    x = np.random.default_rng(1).random((3, 40))
    a, b = simulate(net, {"x": x}), simulate(q, {"x": x}, arithmetic="int64")
    np.testing.assert_array_equal(a.first_spike_steps["y"], b.first_spike_steps["y"])
    # many odd whole weights (levels made for another width) are rounded, not split
    q2, rec2 = quantize(small(np.array([[255.0, 197.0], [-1.0, 3.0]]), v_th=2.0), prof)
    assert not rec2.populations["y"]["exact"] and len(q2.projections) == 1
