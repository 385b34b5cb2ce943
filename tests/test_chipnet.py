"""Loihi's integer registers from a saved network (backends/crosscheck/chipnet.py), hand-worked.

These run without the cross-check environment: they check the number format the workers
apply (docs/hardware.md, "Loihi's number format as Lava and NengoLoihi model it").
"""

from __future__ import annotations

import numpy as np
import pytest

from backends import save
from backends.crosscheck.chipnet import (
    NotExpressible,
    bias_register,
    chip_network,
    raw_weights,
    threshold_register,
)
from backends.crosscheck.env import PACKAGES, find_python310
from compiler.snn import (
    Encoder,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
)


def test_mixed_weights_store_twice_the_mantissa() -> None:
    """w = 3, −5 units (×64 = 192, −320 LSBs): stored 6, −10 (9 bits, lowest dropped),
    weight_exp −1: (6·s) >> 1 << 6 = 192 per spike."""
    stored, exp, mode = raw_weights(np.array([3.0, -5.0]), scale=64)
    assert stored.tolist() == [6, -10] and exp == -1 and mode == "mixed"
    assert ((stored * 1) >> -exp << 6).tolist() == [192, -320]


def test_one_sign_weights_use_eight_bits_and_exponents() -> None:
    stored, exp, mode = raw_weights(np.array([255.0, 1.0]), scale=64)
    assert stored.tolist() == [255, 1] and exp == 0 and mode == "excitatory"
    stored, exp, _ = raw_weights(np.array([1024.0, 8.0]), scale=64)  # 128·2^3, 1·2^3
    assert stored.tolist() == [128, 1] and exp == 3


def test_odd_mixed_mantissa_beyond_127_and_fractions_are_refused() -> None:
    with pytest.raises(NotExpressible, match="mantissa"):
        raw_weights(np.array([255.0, -1.0]), scale=64)   # needs 8 bits + sign
    with pytest.raises(NotExpressible):
        raw_weights(np.array([0.5]), scale=64)            # 32 LSBs: below one input step


def test_threshold_is_strict_and_shifted() -> None:
    """v ≥ θ on whole units is v > θ − 1; raw LSBs: vth << 6 = θ − 1."""
    assert threshold_register(1.0, 64) == 0 and threshold_register(131072.0, 64) == 131071
    assert threshold_register(64 * 300 + 1.0, 1) == 300
    with pytest.raises(NotExpressible, match="vth"):
        threshold_register(131073.0, 64)
    with pytest.raises(NotExpressible):
        threshold_register(100.0, 1)


def test_bias_mantissa_and_exponent() -> None:
    assert bias_register(96.0) == (96, 0) and bias_register(-8190.0) == (-4095, 1)
    assert bias_register(4095.0 * 128) == (4095, 7)
    with pytest.raises(NotExpressible):
        bias_register(4097.0 * 128)


def _net(params: NeuronParams, w: np.ndarray) -> SpikingNetwork:
    return SpikingNetwork(name="n", n_steps=10, populations=[
        Population(id="a", shape={"i": 2}, source=True),
        Population(id="b", shape={"o": 1}, params=params),
        Population(id="c", shape={"o": 1}, params=NeuronParams(v_th=3.0, reset="value"))],
        projections=[MatrixProjection(id="ab", source="a", target="b", contract=("i",),
                                      produce=("o",), weights=w),
                     MatrixProjection(id="bc", source="b", target="c", contract=("o",),
                                      produce=("o",), weights=np.array([[2.0]]),
                                      delays=np.array([[3]]))],
        encoders=[Encoder(port="x", population="a", code=RateCode())])


def test_registers_lags_and_delays_from_the_artifact(tmp_path) -> None:
    """du = 1 is du_chip = 4095 (offset 1); each hop adds a step of lag, kept by delays."""
    params = NeuronParams(du=1.0, dv=0.25, v_th=5.0, reset="value",
                          phases=(Phase(start_step=0, bias=2.0),))
    net = chip_network(save(_net(params, np.array([[1.0], [-2.0]])), tmp_path / "n"))
    b, c = net.populations["b"], net.populations["c"]
    assert (b.du, b.dv, b.vth, b.scale, b.lag) == (4095, 1024, 4, 64, 1)
    assert (b.segments[0]["bias_mant"], b.segments[0]["bias_exp"]) == (128, 0)
    assert any("truncates in LSBs" in n for n in net.notes)  # dv = 1/4 on 64-LSB units
    assert c.lag == 2
    ab, bc = net.projections
    assert ab.weights.tolist() == [[2, -4]] and ab.weight_exp == -1
    assert bc.delays.tolist() == [[3]] and ab.delays.tolist() == [[0, 0]]


def test_non_leaking_current_and_subtractive_reset_are_noted(tmp_path) -> None:
    params = NeuronParams(du=0.0, dv=0.0, v_th=5.0, reset="subtract")
    net = chip_network(save(_net(params, np.array([[1.0], [2.0]])), tmp_path / "n"))
    assert net.populations["b"].leaky_current
    assert any("subtractive reset" in n for n in net.notes)
    assert any("leaks 1/4096" in n for n in net.notes)


def test_reset_to_a_value_other_than_zero_is_refused(tmp_path) -> None:
    params = NeuronParams(v_th=5.0, reset="value", v_reset=1.0)
    with pytest.raises(NotExpressible, match="resets v to 0"):
        chip_network(save(_net(params, np.array([[1.0], [2.0]])), tmp_path / "n"))


def test_environment_pins() -> None:
    assert "lava-nc==0.10.0" in PACKAGES and "numpy==1.26.4" in PACKAGES
    found = find_python310()
    assert found is None or found.exists()


def test_missing_environment_says_how_to_build_it(tmp_path, monkeypatch) -> None:
    from backends.crosscheck.env import CrosscheckEnvError
    from backends.crosscheck.run import run_saved

    monkeypatch.setenv("RADARSNN_CROSSCHECK_ENV", str(tmp_path / "none"))
    with pytest.raises(CrosscheckEnvError, match="--build-env"):
        run_saved("lava", tmp_path, {})


def test_unknown_model_is_refused(tmp_path) -> None:
    from backends.crosscheck.run import run_saved
    from ir.errors import SimulationError

    with pytest.raises(SimulationError, match="unknown chip model 'spinnaker'"):
        run_saved("spinnaker", tmp_path, {})
