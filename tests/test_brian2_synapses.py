"""The Brian2 backend's pure parts (no Brian2 needed): synapse expansion equals the reference
simulator's deliveries, and the neuron code carries the schedule of compiler.snn.neurons."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.brian2 import dense_weights, expand_projection, neuron_code
from backends.reference.delivery import DELIVERY_BUILDERS
from compiler.snn import MatrixProjection, NeuronParams, Phase, Population, StencilProjection


def _reference_matrix(proj, src, tgt, k):
    """Current of one spike of every source neuron, delay class k: (n_post, n_pre)."""
    d = DELIVERY_BUILDERS[type(proj)](proj, src, tgt, False)
    cols = [d.current(k, np.array([n]), 1).ravel() for n in range(src.size)]
    return d.delays[k], np.stack(cols, axis=1)


def _check(proj, src, tgt):
    syn = expand_projection(proj, src, tgt)
    assert np.all(syn.weight != 0)
    n_classes = len(DELIVERY_BUILDERS[type(proj)](proj, src, tgt, False).delays)
    for k in range(n_classes):
        delay, want = _reference_matrix(proj, src, tgt, k)
        np.testing.assert_array_equal(dense_weights(syn, src.size, tgt.size, delay), want)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), reps=st.integers(1, 3), n_in=st.integers(1, 4),
       n_out=st.integers(1, 4), sparse=st.booleans())
def test_matrix_expansion_equals_delivery(seed, reps, n_in, n_out, sparse):
    rng = np.random.default_rng(seed)
    src = Population(id="a", shape={"r": reps, "i": n_in}, source=True)
    tgt = Population(id="b", shape={"o": n_out, "r": reps})  # repetition axis moved
    w = rng.integers(-3, 4, size=(n_in, n_out)).astype(float)
    d = rng.integers(0, 3, size=w.shape)
    if sparse:
        r, c = np.nonzero(w)
        proj = MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                produce=("o",), rows=r, cols=c, values=w[r, c],
                                n_in_out=w.shape, delays=d[r, c])
    else:
        proj = MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                produce=("o",), weights=w, delays=d)
    _check(proj, src, tgt)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), h=st.integers(3, 6), w=st.integers(3, 6),
       edge=st.tuples(st.sampled_from(["wrap", "clip"]), st.sampled_from(["wrap", "clip"])))
def test_stencil_expansion_equals_delivery(seed, h, w, edge):
    rng = np.random.default_rng(seed)
    src = Population(id="a", shape={"x": h, "y": w}, source=True)
    tgt = Population(id="b", shape={"y": w, "x": h})  # axes in another order
    kernel = rng.integers(-2, 3, size=(3, 3)).astype(float)
    proj = StencilProjection(id="k", source="a", target="b", axes=("x", "y"), kernel=kernel,
                             edge=edge, delays=rng.integers(0, 2, size=(3, 3)))
    _check(proj, src, tgt)


def test_neuron_code_schedule_hand_worked():
    p = NeuronParams(du=0.25, dv=0.5, v_th=3.0, reset="subtract",
                     phases=(Phase(start_step=0, bias=0.5),
                             Phase(start_step=2, input_on=False, spiking_on=False)))
    code = neuron_code(p, 4)
    assert code.constants == {"keep_u": 0.75, "keep_v": 0.5, "v_th": 3.0, "v_reset": 0.0}
    assert code.bias.tolist() == [0.5, 0.5, 0.0, 0.0]
    assert code.input_on.tolist() == code.spiking_on.tolist() == [1.0, 1.0, 0.0, 0.0]
    assert code.reset == "v = v - v_th" and "not fired" not in code.threshold
    assert code.update.splitlines()[1:3] == ["ub = u + bias(t)", "v = keep_v * v + ub"]
