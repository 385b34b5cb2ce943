"""Random valid chains compile (and run, with the reference's shapes) or raise a typed error."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st
from test_ir_properties import _random_inputs, chains

from backends.reference import run_program
from compiler.compile import compile_graph
from ir import Graph
from ir.errors import RadarSNNError
from ir.interpreter import evaluate


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains(max_ops=4, with_classifier=False), st.integers(0, 2**32 - 1),
       st.sampled_from([None, "unbounded", "loihi"]))
def test_random_chains_compile_and_run_or_raise_a_typed_error(graph: Graph, seed: int,
                                                              target: str | None) -> None:
    note(graph.to_yaml())
    inputs = _random_inputs(graph, np.random.default_rng(seed))
    try:
        program = compile_graph(graph, target=target, calibration_inputs=inputs, time_steps=32)
    except RadarSNNError as err:  # the only allowed failure: ours, and it says where
        assert str(err)
        return
    result = run_program(program, inputs)
    reference = evaluate(graph, inputs)
    for node in graph.output_ids():
        got, want = result.outputs[node], reference[node]
        assert got.shape == want.shape, node
        assert np.iscomplexobj(got) == np.iscomplexobj(want), node
        assert np.all(np.isfinite(got)), node
