"""``simulate``'s contract: inputs, framing, modes, errors, decoders, rasters, summary."""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import build_plan, closed_form_problems, simulate
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
)
from ir.errors import NetworkError, SimulationError

CODE = LatencyCode(t_max=8, x_min=0.0, x_max=1.0)


def net_of(reset: str = "fire_once", split: str = "none", w: float = 1.0, v_th: float = 1.0,
           decoders=None, code=CODE) -> SpikingNetwork:
    shape = {"i": 3, "part": 2} if split != "none" else {"i": 3}
    contract = ("i", "part") if split != "none" else ("i",)
    n_in = 6 if split != "none" else 3
    return SpikingNetwork(
        name="api", n_steps=10,
        populations=[Population(id="a", shape=shape, source=True),
                     Population(id="b", shape={"o": 2},
                                params=NeuronParams(du=1.0, v_th=v_th, reset=reset))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=contract,
                                      produce=("o",), weights=np.full((n_in, 2), w))],
        encoders=[Encoder(port="x", population="a", code=code, split=split)],
        decoders=decoders if decoders is not None else [
            Decoder(port="t", population="b", kind="spike_time", t_ref=8.0, missing=-1.0)])


def test_frames_axis_convention() -> None:
    net = net_of()
    one = simulate(net, {"x": np.array([1.0, 0.5, 0.0])})
    many = simulate(net, {"x": np.array([[1.0, 0.5, 0.0], [0.0, 0.0, 0.25]])})
    # x = 1 spikes at step 0 → both outputs fire at 0: t_ref - 0 = 8;
    # frame 2: x = .25 spikes at step 6 → 2; x = 0 is step 8 = t_max: no spike
    assert one.outputs["t"].tolist() == [8.0, 8.0]
    assert many.outputs["t"].tolist() == [[8.0, 8.0], [2.0, 2.0]]
    assert (one.n_frames, many.n_frames) == (1, 2)
    assert one.first_spike_steps["b"].shape == (1, 2)  # diagnostics always carry frames
    assert many.spike_counts == {"a": 3, "b": 4}
    assert many.synaptic_events == {"w": 6}


def test_auto_picks_closed_when_eligible_and_step_otherwise() -> None:
    assert simulate(net_of(), {"x": np.ones(3)}, mode="auto").mode == "closed"
    assert simulate(net_of("subtract"), {"x": np.ones(3)}, mode="auto").mode == "step"


def test_closed_on_ineligible_network_says_why() -> None:
    with pytest.raises(SimulationError, match=r"population 'b' has reset='subtract'.*"
                                              r"mode='step'"):
        simulate(net_of("subtract"), {"x": np.ones(3)}, mode="closed")
    rec = net_of()
    rec.projections.append(MatrixProjection(id="self", source="b", target="b", contract=("o",),
                                            produce=("o",), weights=np.eye(2),
                                            delays=np.ones((2, 2), int)))
    assert any("cycle" in p for p in closed_form_problems(rec))
    with pytest.raises(SimulationError, match="cycle"):
        simulate(rec, {"x": np.ones(3)}, mode="closed")


@pytest.mark.parametrize("inputs, match", [
    ({}, r"missing \['x'\]"),
    ({"x": np.ones(3), "y": np.ones(3)}, r"unexpected \['y'\]"),
    ({"x": np.ones(4)}, r"input 'x': expected shape \(3,\) .* got \(4,\)"),
    ({"x": np.ones((2, 2, 3))}, r"input 'x': expected shape"),
    ({"x": np.ones((0, 3))}, r"n_frames >= 1"),
    ({"x": np.array([1.0, np.nan, np.inf])}, r"input 'x': 2 of 3 values are NaN or Inf"),
    ({"x": np.ones(3, complex)}, r"input 'x': complex values need .* split is 'none'"),
    ({"x": np.array(["a", "b", "c"])}, r"input 'x': expected a numeric array"),
])
def test_bad_inputs(inputs: dict, match: str) -> None:
    with pytest.raises(SimulationError, match=match):
        simulate(net_of(), inputs)


def test_frames_must_agree_across_ports() -> None:
    net = net_of()
    net.populations.append(Population(id="c", shape={"j": 2}, source=True))
    net.encoders.append(Encoder(port="z", population="c", code=CODE))
    with pytest.raises(SimulationError, match="disagree on the frames axis"):
        simulate(net, {"x": np.ones((2, 3)), "z": np.ones(2)})
    assert simulate(net, {"x": np.ones((2, 3)), "z": np.ones((2, 2))}).n_frames == 2


def test_unknown_mode_and_arithmetic() -> None:
    with pytest.raises(SimulationError, match="mode 'fast'"):
        simulate(net_of(), {"x": np.ones(3)}, mode="fast")
    with pytest.raises(SimulationError, match="arithmetic 'float32'"):
        simulate(net_of(), {"x": np.ones(3)}, arithmetic="float32")


def test_int64_refuses_fractional_parameters_naming_them() -> None:
    with pytest.raises(SimulationError, match=r"projection 'w'.*whole-number weights.*quantize"):
        simulate(net_of(w=0.5), {"x": np.ones(3)}, arithmetic="int64")
    with pytest.raises(SimulationError, match=r"population 'b'.*v_th=1.5.*quantize"):
        simulate(net_of(v_th=1.5), {"x": np.ones(3)}, arithmetic="int64")
    r = simulate(net_of(w=2.0, v_th=3.0), {"x": np.ones(3)}, arithmetic="int64")
    assert r.arithmetic == "int64" and r.outputs["t"].tolist() == [8.0, 8.0]


def test_complex_input_through_re_im_split_round_trips() -> None:
    # the source itself decoded by spike time: value = 1 - t/8 for the latency code
    decs = [Decoder(port="z", population="a", kind="spike_time", combine="re_im",
                    scale=1 / 8, t_ref=8.0)]
    z = np.array([1.0 + 0.5j, 0.25 + 0.75j, 0.125 + 0.0j])
    r = simulate(net_of(split="re_im", decoders=decs), {"x": z})
    np.testing.assert_array_equal(r.outputs["z"], z)  # all on the 1/8 grid: exact


def test_decoder_kinds() -> None:
    decs = [Decoder(port="n", population="b", kind="count", scale=2.0, offset=1.0),
            Decoder(port="v", population="b", kind="membrane", scale=0.5),
            Decoder(port="s", population="b", kind="spiked")]
    r = simulate(net_of("subtract", w=0.5, decoders=decs), {"x": np.array([1.0, 0.0, 0.0])})
    # one input spike at step 0 with weight .5 into IF (du = 1): v = .5, no spike
    assert r.outputs["n"].tolist() == [1.0, 1.0]
    assert r.outputs["v"].tolist() == [0.25, 0.25]
    assert r.outputs["s"].tolist() == [0.0, 0.0]


def test_membrane_of_a_source_is_refused() -> None:
    decs = [Decoder(port="v", population="a", kind="membrane")]
    with pytest.raises(NetworkError, match="decoder 'v'.*spike source"):
        simulate(net_of(decoders=decs), {"x": np.ones(3)})


def test_rasters_and_their_limit() -> None:
    net = net_of()
    r = simulate(net, {"x": np.ones((2, 3))}, record_spikes=True)
    assert r.spikes["a"].shape == (2, 10, 3) and r.spikes["b"].shape == (2, 10, 2)
    assert r.spikes["a"][:, 0].all() and r.spikes["a"].sum() == 6
    # 2 frames × 10 steps × 5 neurons = 100 bytes
    with pytest.raises(SimulationError, match=r"100 bytes .* raster_limit_bytes=99"):
        simulate(net, {"x": np.ones((2, 3))}, record_spikes=True, raster_limit_bytes=99)
    assert simulate(net, {"x": np.ones(3)}).spikes is None


def test_rate_code_counts_match_the_code() -> None:
    code = RateCode(max_rate=0.5, phase=0.25)
    x = np.array([1.0, 0.5, 0.3])
    for mode in ("step", "closed"):
        r = simulate(net_of(code=code), {"x": x}, mode=mode, record_spikes=True)
        np.testing.assert_array_equal(r.spikes["a"][0].sum(axis=0), code.spike_counts(x, 10))


def test_plan_reuse_and_mismatch() -> None:
    net = net_of()
    plan = build_plan(net)
    r = simulate(net, {"x": np.ones(3)}, plan=plan)
    assert r.outputs["t"].tolist() == [8.0, 8.0]
    with pytest.raises(SimulationError, match="build_plan"):
        simulate(net_of(), {"x": np.ones(3)}, plan=plan)


def test_summary_mentions_mode_and_counts() -> None:
    text = simulate(net_of(), {"x": np.ones(3)}, mode="closed").summary()
    assert text.splitlines()[0] == ("mode=closed arithmetic=float64 frames=1 steps=10 spikes=5 "
                                    "synaptic_events=6")


def test_delivery_registry_is_explicit() -> None:
    from backends.reference import DELIVERY_BUILDERS
    only_stencils = {k: v for k, v in DELIVERY_BUILDERS.items() if k is not MatrixProjection}
    with pytest.raises(SimulationError, match=r"projection 'w': no delivery for kind 'matrix'"):
        build_plan(net_of(), builders=only_stencils)


@pytest.mark.parametrize("mode", ["step", "closed"])
def test_network_without_inputs_runs_on_bias(mode: str) -> None:
    # bias 0.25 per step, no leak: v = 0.25·(t + 1) reaches 1 at step 3
    net = SpikingNetwork(name="bias", n_steps=6, populations=[Population(
        id="b", shape={"o": 1}, params=NeuronParams(v_th=1.0, reset="fire_once",
                                                    phases=(Phase(start_step=0, bias=0.25),)))])
    r = simulate(net, {}, mode=mode)
    assert r.first_spike_steps["b"].tolist() == [[3]] and r.n_frames == 1
