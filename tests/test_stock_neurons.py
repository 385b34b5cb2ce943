"""Every motif compiled for ``loihi`` uses only what the chip's stock LIF has, or is refused.

Loihi 1's compartment (Lava 0.10's and NengoLoihi 1.1's bit-accurate models agree): the
current decays by at least 1/4096 a step, a spike resets ``v`` to 0, no fire-once, no
threshold or input change mid-run, no resonate-and-fire neurons. The profile says so in its
neuron fields (``compiler/hardware/neuron_features.py``); a compile for ``loihi`` gives a
network whose every population needs none of the missing features, or a ``CompileError``
naming the node, the feature and the fix.
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import run_program, simulate
from compiler.accuracy.contract import Contract
from compiler.accuracy.select import search
from compiler.compile import compile_graph
from compiler.hardware import load_profile
from compiler.hardware.neuron_features import missing_features
from compiler.passes.relay import relay_long_delays
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir import Graph
from ir.errors import BudgetError, CompileError

LOIHI = load_profile("loihi")
SAMPLES = np.random.default_rng(1).normal(size=(2, 16))


def _dft(tail: list[dict] | None = None) -> Graph:
    nodes = [{"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 16}},
             {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin"}]
    nodes += tail or []
    nodes.append({"id": "o", "op": "output", "input": nodes[-1]["id"]})
    return Graph.from_dict({"name": "dft", "nodes": nodes})


def _cfar(kind: str) -> Graph:
    extra = {"k": 20} if kind == "os" else {}
    return Graph.from_dict({"name": "cfar", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 32, "doppler": 16}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "x", "kind": kind, "guard": [1, 1],
         "train": [2, 2], "alpha": 3.0, "edge": ["clip", "wrap"], **extra},
        {"id": "o", "op": "output", "input": "det"}]})


def _maps(seed: int = 3, n: int = 2) -> np.ndarray:
    m = np.random.default_rng(seed).exponential(1.0, size=(n, 32, 16))
    m[:, 5, 3] = m[:, 20, 11] = 30.0
    return m


def _stock_only(program) -> None:
    for net in program.networks:
        for pop in net.populations:
            if not pop.source:
                assert missing_features(pop.params, LOIHI) == [], pop.id


#: motif -> (graph, calibration, compile options, the refusal's features or None: compiles)
REFUSED = {
    "time-coded S-FT": (_dft(), {"motifs": {"dft": "time"}},
                        r"non-leaking current.*fire-once.*spiking gate.*input gate"),
    "rate S-DFT": (_dft(), {"motifs": {"dft": "rate"}, "time_steps": 64},
                   r"subtractive reset"),
    "S-FFT": (_dft(), {"motifs": {"dft": "time-fft"}, "time_steps": 32}, r"fire-once"),
    "resonator": (_dft(), {"motifs": {"dft": "resonator"}}, r"resonate-and-fire"),
    "magnitude l1": (_dft([{"id": "m", "op": "magnitude", "input": "f"}]),
                     {"motifs": {"dft": "host", "m": "l1"}}, r"non-leaking current"),
}


@pytest.mark.parametrize("motif", list(REFUSED))
def test_a_motif_the_stock_lif_cannot_run_is_refused_naming_the_feature(motif: str) -> None:
    graph, kw, features = REFUSED[motif]
    node = "m" if motif.startswith("magnitude") else "f"
    with pytest.raises(CompileError, match=rf"node '{node}' \(motif .*needs .*{features}.*"
                                          rf"which the stock neurons of loihi lack; use a "
                                          rf"target whose neurons have it \(loihi2\) or "
                                          rf"motifs=\{{'{node}': 'host'\}}") as err:
        compile_graph(graph, "loihi", calibration_inputs={"x": SAMPLES}, **kw)
    assert "\n" not in str(err.value) and err.value.node == node
    assert not isinstance(err.value, BudgetError)  # a motif the chip lacks, not a budget
    if node == "f":  # the fix it names (the magnitude's: a demand-model error elsewhere)
        compile_graph(graph, "loihi2", calibration_inputs={"x": SAMPLES}, **kw)


def test_ca_cfar_is_refused_on_loihi_its_ramp_needs_a_non_leaking_current() -> None:
    with pytest.raises(CompileError, match=r"node 'det' \(motif time, population 'det/det'\) "
                                          r"needs a non-leaking current.*fire-once.*spiking gate.*"
                                          r"input gate"):
        compile_graph(_cfar("ca"), "loihi", calibration_inputs={"x": _maps()})


def test_os_cfar_on_loihi_resets_to_zero_and_detects_as_fire_once() -> None:
    """Each input cell spikes once and only the CUT weight is positive: after its spike the
    membrane only falls, so the reset to 0 gives the fire-once detections, spike for spike."""
    cal = {"x": _maps()}
    stock = compile_graph(_cfar("os"), "loihi", calibration_inputs=cal)
    det = stock.networks[0].population["det/det"].params
    assert (det.reset, det.v_reset, det.du, det.phases[0].spiking_on) == ("value", 0.0, 1.0, True)
    _stock_only(stock)
    once = compile_graph(_cfar("os"), LOIHI.model_copy(update={"fire_once": "programmable"}),
                         calibration_inputs=cal)
    assert once.networks[0].population["det/det"].params.reset == "fire_once"
    x = _maps(seed=9, n=3)
    a, b = (run_program(p, {"x": x}, mode="step", arithmetic="int64") for p in (stock, once))
    assert a.values["det"].sum() > 10 and np.array_equal(a.values["det"], b.values["det"])
    assert a.spike_counts["det/det"] == a.values["det"].sum()  # one spike per detection


def test_the_classifier_on_loihi_needs_layers_that_reset_to_zero(tmp_path) -> None:
    """Layers that subtract are refused; with reset to 0 every population is stock: the input
    relays and the max-pool OR neurons (dv = 1, which Loihi's 12-bit dv cannot hold) run with
    dv = 0, the same spikes (their weights reach the threshold: after each step v = 0)."""
    from compiler.classifier import save_weights
    from ir.ops.classify import LIF, Classifier, Conv2d, Integrator, LevelsEncoding, Pool

    def op(reset: str) -> Classifier:
        return Classifier(num_classes=2, weights=str(tmp_path / "w.npz"),
                          encoding=LevelsEncoding(levels=(0.0,)),
                          layers=(Conv2d(channels=2, kernel=(2, 2), stride=(2, 2),
                                         neuron=LIF(dv=0.25, reset=reset)),
                                  Pool(mode="max", size=(2, 2)), Integrator(units=2)))

    rng = np.random.default_rng(5)
    save_weights(tmp_path / "w.npz", {k: rng.normal(0.8, 0.6, shape) for k, shape in
                                      op("value").weight_shapes("cls", (4, 4)).items()})

    def compiled(reset: str, target=LOIHI):
        return compile_graph(Graph.from_dict({"name": "clf", "nodes": [
            {"id": "roi", "op": "input", "shape": {"frame": 3, "doppler": 4, "range": 4},
             "domain": "db"},
            {"id": "cls", "op": "classifier", "input": "roi", **op(reset).params()},
            {"id": "out", "op": "output", "input": "cls"}]}), target)

    with pytest.raises(CompileError, match=r"node 'cls' \(motif snn, population 'cls/l0'\) "
                                          r"needs subtractive reset"):
        compiled("subtract")
    stock = compiled("value")
    _stock_only(stock)
    pops = stock.networks[0].population
    assert (pops["cls/l0"].params.reset, pops["cls/l0"].params.v_reset) == ("value", 0.0)
    assert pops["cls/input"].params.dv == pops["cls/l1"].params.dv == 0.0
    full = compiled("value", LOIHI.model_copy(update={"full_voltage_decay": True}))
    assert full.networks[0].population["cls/l1"].params.dv == 1.0
    x = rng.normal(0.5, 1.0, size=(6, 3, 4, 4))
    a, b = (run_program(p, {"roi": x}, mode="step", arithmetic="int64") for p in (stock, full))
    assert a.spike_counts == b.spike_counts and a.spike_counts["cls/l1"] > 0
    np.testing.assert_array_equal(a.values["cls"], b.values["cls"])


def test_delay_relays_reset_to_zero_on_loihi() -> None:
    net = SpikingNetwork(
        name="d", n_steps=200,
        populations=[Population(id="a", shape={"i": 2}, source=True),
                     Population(id="b", shape={"i": 2}, params=NeuronParams(du=1.0, v_th=1.0,
                                                                            reset="value"))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                      produce=("i",), weights=np.eye(2),
                                      delays=np.full((2, 2), 150))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))])
    relayed = relay_long_delays(net, LOIHI, "relay")
    relays = [p for p in relayed.populations if "__relay" in p.id]
    assert relays and all(p.params.reset == "value" and p.params.v_reset == 0 for p in relays)
    assert all(missing_features(p.params, LOIHI) == [] for p in relayed.populations
               if not p.source)
    x = np.array([[1.0, 0.25]])
    a, b = (simulate(n, {"x": x}, mode="step") for n in (net, relayed))
    assert np.array_equal(a.first_spike_steps["b"], b.first_spike_steps["b"])
    assert a.first_spike_steps["b"].min() >= 150


def test_the_motif_search_skips_rungs_the_stock_lif_refuses() -> None:
    """CA-CFAR on loihi: both spiking rungs are refused (a typed error), the host rung holds."""
    graph, cal = _cfar("ca"), {"x": _maps()}

    def build(motifs, options):
        return compile_graph(graph, "loihi", calibration_inputs=cal, motifs=motifs,
                             options=dict(options))

    program, sel = search(["cfar"], build, lambda p: Contract(stages=[], n_frames=1))
    assert [a.config["cfar"] for a in sel.attempts] == ["time", "time(cfar_steps=300)",
                                                       "time(cfar_steps=1000)", "host"]
    assert all("non-leaking current" in a.error for a in sel.attempts[:2])
    assert sel.host_ops == ["cfar"] and not program.networks


def test_profile_neuron_fields_are_typed(tmp_path) -> None:
    import yaml

    doc = {**LOIHI.model_dump(), "reset": "sometimes"}
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(doc))
    with pytest.raises(CompileError, match=r"field 'reset' = 'sometimes'"):
        load_profile(tmp_path / "p.yaml")
    offset = LOIHI.number_format.current_decay_offset_lsb
    assert (offset, LOIHI.reset, LOIHI.fire_once) == (1, "zero", "none")
    assert not (LOIHI.threshold_schedule or LOIHI.input_gate or LOIHI.resonate_and_fire)
    for name in ("loihi2", "spinnaker2", "unbounded"):
        p = load_profile(name)
        assert (p.number_format.current_decay_offset_lsb, p.reset, p.fire_once) == (
            0, "programmable", "programmable")


def _ramp(reset: str, weight: float, bits: int | None = 4) -> SpikingNetwork:
    return SpikingNetwork(
        name="ov", n_steps=4, meta={"state_bits": bits} if bits else {},
        populations=[Population(id="a", shape={"i": 1}, source=True),
                     Population(id="b", shape={"o": 2}, params=NeuronParams(
                         du=0.0, dv=0.0, v_th=100.0, reset=reset))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                      produce=("o",), weights=np.array([[weight, -weight]]))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])


def test_state_beyond_the_chips_range_is_counted_by_hand() -> None:
    """4-bit state: ±7. One input spike at step 0, weights ±3, a ramp (du = dv = 0):
    u = ±3 every step, v = ±3, ±6, ±9, ±12 — steps 2 and 3 of both neurons are beyond."""
    x = np.array([[1.0]])
    step = simulate(_ramp("value", 3.0), {"x": x}, mode="step", arithmetic="int64")
    assert step.first_spike_steps["a"].tolist() == [[0]]
    assert step.state_overflow == {"b": 4}
    # the closed form does not step: it counts the final membranes ±12 (a lower bound)
    closed = simulate(_ramp("fire_once", 3.0), {"x": x}, mode="closed", arithmetic="int64")
    assert closed.mode == "closed" and closed.state_overflow == {"b": 2}
    # weights ±9: u = ±9 is beyond from step 0 (where the chip's u wraps): every step
    assert simulate(_ramp("value", 9.0), {"x": x}, mode="step",
                    arithmetic="int64").state_overflow == {"b": 8}
    # float64 counts the same; no state width (not quantized for a chip): nothing counted
    assert simulate(_ramp("value", 3.0), {"x": x}, mode="step").state_overflow == {"b": 4}
    assert simulate(_ramp("value", 3.0, bits=None), {"x": x}, mode="step",
                    arithmetic="int64").state_overflow == {}
    assert "2 neuron-steps" not in step.summary() and "4 neuron-steps beyond" in step.summary()


def test_a_program_quantized_for_loihi_carries_its_state_width() -> None:
    program = compile_graph(_cfar("os"), "loihi", calibration_inputs={"x": _maps()})
    assert program.networks[0].meta["state_bits"] == 18
    res = run_program(program, {"x": _maps(seed=4)}, mode="step", arithmetic="int64")
    assert res.state_overflow == {}  # the OS-CFAR's membrane stays within ±(2^17 − 1) units
