"""Generated decoders divide per-index stage gains out exactly like backends.reference.

A decoder with ``gain_axis``/``gains`` reads ``gains[i]·y`` from its population and
divides by ``gains[i]`` before ``combine`` (:mod:`backends.reference.decoding`); the
generated package must do the same arithmetic so its outputs are bit-identical.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from backends.emit import emit_numpy
from backends.emit.run_package import run_package
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir import Graph

N_CHIRPS, N_SAMPLES = 8, 32


def _range_doppler() -> Graph:
    return Graph.from_dict({"name": "rd", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": N_CHIRPS, "sample": N_SAMPLES}},
        {"id": "rng", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range",
         "keep": "positive"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler"},
        {"id": "o", "op": "output", "input": "dop"}]})


def _strong_and_weak(seed: int) -> np.ndarray:
    """A DC of 100 (range bin 0) over a weak moving tone at range bin 5 and unit noise."""
    n = np.arange(N_SAMPLES)[None, :]
    c = np.arange(N_CHIRPS)[:, None]
    noise = np.random.default_rng(seed).normal(size=(N_CHIRPS, N_SAMPLES))
    return 100.0 + 1.2 * np.cos(2 * np.pi * (5 * n / N_SAMPLES + 2 * c / N_CHIRPS)) + noise


@pytest.mark.parametrize(("charging", "kind"), [("constant", "spike_time"),
                                                ("auto", "spike_table")])
def test_two_stage_sft_with_stage_gains_matches_the_reference(charging, kind, tmp_path):
    x = _strong_and_weak(0)
    program = compile_graph(_range_doppler(), None, calibration_inputs={"x": x},
                            time_steps=32,
                            options={"charging": charging, "static_split": "off"})
    (net,) = program.networks
    assert net.meta["stage_gains"]["rng"]["axis"] == "range"  # default stage_gains="auto"
    (dec,) = net.decoders
    assert (dec.kind, dec.gain_axis, len(dec.gains)) == (kind, "range", N_SAMPLES // 2)
    assert min(dec.gains) == 1.0 and max(dec.gains) > 10.0
    y = 0.8 * _strong_and_weak(1)  # another frame, inside the calibrated range
    ref = run_program(program, {"x": y}, mode="step")
    out, counts = run_package(emit_numpy(program, tmp_path), {"x": y})
    np.testing.assert_array_equal(out["o"], ref.outputs["o"])
    assert counts == [s.spike_counts for s in ref.simulations]
    # the check can fail: the same spikes decoded without the gains differ
    plain = replace(net, decoders=[dec.model_copy(update={"gain_axis": None, "gains": ()})])
    ungained = simulate(plain, {"x": y}, mode="step").outputs["dop"]
    assert not np.array_equal(ungained, ref.simulations[0].outputs["dop"])


def _gained_network() -> SpikingNetwork:
    """Latency inputs ``in`` (r: 3, i: 2) into non-leaky IF sums ``out`` (r: 3, o: 1)."""
    return SpikingNetwork(
        name="gains", n_steps=6,
        populations=[Population(id="in", shape={"r": 3, "i": 2}, source=True),
                     Population(id="out", shape={"r": 3, "o": 1},
                                params=NeuronParams(du=1.0, dv=0.0, v_th=100.0))],
        projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1)))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="in", kind="spike_time", t_ref=4.0,
                          missing=-1.0, gain_axis="r", gains=(1.0, 2.0, 4.0)),
                  Decoder(port="n", population="in", kind="count", offset=0.5,
                          gain_axis="i", gains=(2.0, 0.5)),
                  Decoder(port="v", population="out", kind="membrane", scale=3.0, offset=1.0,
                          gain_axis="r", gains=(1.0, 2.0, 4.0))])


@pytest.mark.parametrize("arithmetic", ["float64", "int64"])
def test_hand_worked_gains_on_every_value_kind(arithmetic, tmp_path):
    # spike steps t = 4 - 4x: [[0, 2], [0, none], [2, 2]]; arrived inputs per r: 2, 1, 2
    x = np.array([[1.0, 0.5], [1.0, 0.0], [0.5, 0.5]])
    frames = np.stack([x, x[::-1]])
    net = _gained_network()
    ref = simulate(net, {"x": frames}, mode="step", arithmetic=arithmetic)
    # spike_time (4 - t) / g_r, missing stays -1
    assert ref.outputs["t"][0].tolist() == [[4.0, 2.0], [2.0, -1.0], [0.5, 0.5]]
    # count (n + 0.5) / g_i
    assert ref.outputs["n"][0].tolist() == [[0.75, 3.0], [0.75, 1.0], [0.75, 3.0]]
    # membrane (3 v + 1) / g_r with v = 2, 1, 2
    assert ref.outputs["v"][0].tolist() == [[7.0], [2.0], [1.75]]
    out, counts = run_package(emit_numpy(net, tmp_path, arithmetic=arithmetic), {"x": frames})
    assert sorted(out) == ["n", "t", "v"]
    for port in out:
        np.testing.assert_array_equal(out[port], ref.outputs[port], err_msg=port)
    assert counts == [ref.spike_counts]
