"""Brian2 runs the resonator motif with the reference's spike steps (issue 22).

The fixed-point (loihi2) networks, plain or renormalised every 4 steps, are whole numbers
throughout, so Brian2's own operation
order gives exactly the reference's bits: every compartment spikes on the same step and
the decoded outputs are equal.
"""

from __future__ import annotations

import numpy as np
import pytest

b2 = pytest.importorskip("brian2", reason="Brian2 is the optional extra 'brian2' "
                         "(pip install 'radarsnn[brian2]'); CI installs it")

from backends.brian2 import simulate_brian2  # noqa: E402
from backends.reference import simulate  # noqa: E402
from compiler.compile import compile_graph  # noqa: E402
from ir import Graph  # noqa: E402


def _network(complex_in: bool, readout: str, renorm="off"):
    n = 16
    g = Graph.from_dict({"name": "res", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": n}, "complex": complex_in},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "window": "hann"},
        {"id": "o", "op": "output", "input": "f"}]})
    rng = np.random.default_rng(7)
    x = rng.normal(size=(2, n)) + (1j * rng.normal(size=(2, n)) if complex_in else 0)
    p = compile_graph(g, "loihi2", motifs={"f": "resonator"}, calibration_inputs={"x": x},
                      time_steps=32, options={"resonator_readout": readout,
                                                  "resonator_renorm": renorm})
    return p.networks[0], x


@pytest.mark.parametrize("complex_in", [False, True])
@pytest.mark.parametrize("readout", ["time", "graded"])
@pytest.mark.parametrize("renorm", ["off", 4])
def test_brian2_spike_steps_equal_the_reference(complex_in, readout, renorm):
    net, x = _network(complex_in, readout, renorm)
    assert net.population["f/out"].params.renorm_steps == (0 if renorm == "off" else 4)
    ref = simulate(net, {"x": x}, mode="step")
    got = simulate_brian2(net, {"x": x})
    for pid, steps in ref.first_spike_steps.items():
        np.testing.assert_array_equal(got.first_spike_steps[pid], steps, err_msg=pid)
    np.testing.assert_array_equal(got.outputs["f"], ref.outputs["f"])
    assert got.synaptic_events == ref.synaptic_events
