"""Fuzz: large batches — far frames count like frame 0, and big closed-form batches run.

Random CFAR networks (OS or CA, 1-D or 2-D maps, guard and training sizes, clipped or
wrapped edges) are compiled once per example; then

* every delivery's synaptic-event count of the same neurons in a far frame (up to frame
  ``10^7``) equals frame 0's (``np.take(mode="wrap")`` once looped over the frame index per
  event: a CFAR batch was quadratic in frames);
* a closed-form run of up to 4 000 frames gives one map per frame, and the guard's estimate
  of it is positive and finite.

What those cost — the far count as cheap as frame 0's, the closed run within ten times the
guard's estimate and the estimate within ten times the run — are speed claims, measured by
``benchmarks/speed_claims.py`` (wall-clock bounds do not belong in tests).
"""

from __future__ import annotations

import numpy as np
from fuzz_support import budget
from hypothesis import given, note
from hypothesis import strategies as st

from backends.reference import build_plan, simulate
from backends.reference.guards import estimate_simulation
from compiler.compile import compile_graph
from ir import Graph


@st.composite
def cfar_graphs(draw: st.DrawFn) -> Graph:
    """A CFAR chain on a random power map that the compiler accepts."""
    two_d = draw(st.booleans())
    axes = ["range", "doppler"] if two_d else ["range"]
    guard = [draw(st.integers(0, 2)) for _ in axes]
    train = [draw(st.integers(1, 3)) for _ in axes]
    shape = {a: draw(st.integers(2 * (g + t) + 1, 32 if a == "range" else 16))
             for a, g, t in zip(axes, guard, train, strict=True)}
    kind = draw(st.sampled_from(["os", "ca"]))
    params = {"kind": kind, "axes": axes, "guard": guard, "train": train, "alpha": 2.0,
              "edge": [draw(st.sampled_from(["clip", "wrap"])) for _ in axes]}
    if kind == "os":
        n_train = int(np.prod([2 * (g + t) + 1 for g, t in zip(guard, train, strict=True)])
                      - np.prod([2 * g + 1 for g in guard]))
        params["k"] = draw(st.integers(1, n_train))
    return Graph.from_dict({"name": "fuzz-cfar", "nodes": [
        {"id": "rd", "op": "input", "shape": shape, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "rd", **params},
        {"id": "out", "op": "output", "input": "det"}]})


def _network(graph: Graph):
    shape = tuple(graph.infer_types()["rd"].axes.values())
    rng = np.random.default_rng(0)
    program = compile_graph(graph, target=None,
                            calibration_inputs={"rd": rng.exponential(size=(16, *shape))})
    (net,) = [s.network for s in program.segments if s.kind == "spiking"]
    return net, shape


@budget(0.02)
@given(cfar_graphs(), st.integers(1, 10**7), st.integers(1, 4_000))
def test_far_frames_and_large_batches(graph, frame, n_frames) -> None:
    net, shape = _network(graph)
    note(f"{graph.to_dict()['nodes'][1]}, frame {frame}, {n_frames} frames")
    for dl in build_plan(net).deliveries.values():
        events = np.arange(dl.src_size).repeat(4)
        far = dl.n_events(0, events + frame * dl.src_size)
        assert far == dl.n_events(0, events), f"{dl.id}: frame {frame} counts differently"
    x = np.random.default_rng(n_frames).exponential(size=(n_frames, *shape))
    result = simulate(net, {"rd": x}, mode="closed", out_of_range="clip")
    assert result.mode == "closed"
    assert [v.shape for v in result.outputs.values()] == [(n_frames, *shape)]
    estimate = estimate_simulation(net, n_frames, mode="closed").time_s
    assert 0 < estimate < float("inf")
