"""Per-neuron parameter scales (``NeuronParams.scale_axis``/``scales``): a hand-worked trace,
and the same spikes from the step engine, the closed form, both arithmetics, generated code
and Brian2."""

from __future__ import annotations

import numpy as np
import pytest

from backends.emit import emit_numpy
from backends.emit.run_package import run_package
from backends.reference import closed_form_problems, simulate
from backends.reference.continuous import continuous_problems
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    SpikingNetwork,
)
from ir.errors import NetworkError


def _ramp(scales=(1.0, 4.0), v_th=6.0) -> SpikingNetwork:
    params = NeuronParams(du=0.0, dv=0.0, v_th=v_th, reset="fire_once", scale_axis="r",
                          scales=scales,
                          phases=(Phase(start_step=0, spiking_on=False),
                                  Phase(start_step=2, bias=1.0, input_on=False)))
    return SpikingNetwork(
        name="scaled", n_steps=12,
        populations=[Population(id="x", shape={"i": 1}, source=True),
                     Population(id="y", shape={"r": 2}, params=params)],
        projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
                                      produce=("r",), weights=np.array([[2.0, 2.0]]))],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=2, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="y", kind="spike_time", scale=-1.0, missing=-1.0),
                  Decoder(port="v", population="y", kind="membrane")])


def test_hand_worked_trace():
    """Input spike at step 0 with weight 2: u = 2 from step 0, v = 2, 4 after the silent
    stage [0, 2).  Charging adds c·1 per step against c·6: neuron 0 (c = 1) reaches 5, 6 →
    fires at step 3; neuron 1 (c = 4) reaches 8, 12, 16, 20, 24 → fires at step 6 — the
    unscaled neuron fed V/c = 1: 2, 3, 4, 5, 6."""
    for mode in ("step", "closed"):
        for arithmetic in ("float64", "int64"):
            out = simulate(_ramp(), {"x": np.array([1.0])}, mode=mode, arithmetic=arithmetic)
            assert out.outputs["t"].tolist() == [3.0, 6.0], (mode, arithmetic)
            # fire-once keeps integrating: v = 4 + 10·c at the end (steps 2..11)
            assert out.outputs["v"].tolist() == [14.0, 44.0], (mode, arithmetic)


def test_scales_validate_against_the_population():
    with pytest.raises(ValueError, match="go together"):
        NeuronParams(scale_axis="r")
    with pytest.raises(ValueError, match="positive"):
        NeuronParams(scale_axis="r", scales=(1.0, 0.0))
    net = _ramp(scales=(1.0, 2.0, 4.0))
    with pytest.raises(NetworkError, match="3 per-neuron scales along 'r'"):
        net.validate()
    assert closed_form_problems(_ramp()) == []
    assert "per-neuron scales" in continuous_problems(_ramp())[0]


def test_generated_code_and_brian2_match(tmp_path):
    rng = np.random.default_rng(0)
    net = _ramp(scales=(2.0, 8.0), v_th=5.0)
    x = {"x": rng.uniform(0, 1, size=(3, 1))}
    ref = simulate(net, x, mode="step")
    out, _ = run_package(emit_numpy(net, tmp_path), x)
    np.testing.assert_array_equal(out["t"], ref.outputs["t"])
    np.testing.assert_array_equal(out["v"], ref.outputs["v"])
    pytest.importorskip("brian2")
    from backends.brian2 import simulate_brian2

    b2 = simulate_brian2(net, x)
    np.testing.assert_array_equal(b2.outputs["t"], ref.outputs["t"])
