"""The resonator DFT on every built-in profile and board: each read-out the target accepts
decodes the numpy DFT within a stated bound (a membrane decoder follows the quantized
state unit, so no target reads a scaled copy); a target without resonate-and-fire neurons
refuses the motif, naming them."""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.hardware import BUILTIN_BOARDS, BUILTIN_PROFILES, load_profile
from ir import Graph
from ir.errors import RadarSNNError

N = 64
#: Largest |error| over the largest |X|: the time read-out rounds each part to half a step of
#: 256 (plus the 12-bit-or-wider input levels and the fixed-point drift bound, 0.001 here);
#: the graded read-out has no read-out rounding.
BOUND = {"time": 0.006, "graded": 0.004}


def _graph() -> Graph:
    return Graph.from_dict({"name": "res", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 3, "sample": N}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})


def _signal() -> np.ndarray:
    t = np.arange(N)
    return np.random.default_rng(0).normal(size=(3, N)) + 3 * np.cos(2 * np.pi * 5 * t / N)


@pytest.mark.parametrize("target", [*BUILTIN_PROFILES, *BUILTIN_BOARDS])
def test_every_accepted_readout_decodes_the_numpy_dft(target):
    x = _signal()
    ref = np.fft.fft(x, axis=1)[:, :N // 2]
    accepted, refused = [], []
    for readout in ("time", "graded"):
        try:
            p = compile_graph(_graph(), target, motifs={"f": "resonator"},
                              calibration_inputs={"x": x}, time_steps=256,
                              options={"resonator_readout": readout})
        except RadarSNNError as err:  # a refused read-out is a typed error, never a wrong one
            refused.append(str(err))
            continue
        y = run_program(p, {"x": x}, mode="closed").outputs["o"]
        err = np.abs(y - ref).max() / np.abs(ref).max()
        assert err < BOUND[readout], (target, readout, err)
        accepted.append(readout)
    if not load_profile(target).resonate_and_fire:  # Loihi 1's stock neurons are LIF
        # the time read-out names the missing neuron; graded is refused first for binary spikes
        assert accepted == [] and "resonate-and-fire" in refused[0], refused
        assert "graded spikes" in refused[1] or "resonate-and-fire" in refused[1], refused
        return
    assert "time" in accepted  # every target with resonators takes the time read-out
