"""Resource guards: the compile and simulation estimates (hand-worked numbers), the refusals
before anything is allocated, and the options that set the limits."""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import run_program, simulate
from backends.reference.guards import MAX_MEMORY_BYTES, estimate_simulation, frames_in
from compiler.compile import EXTRA_OPTIONS, compile_graph
from compiler.compile_guards import check_compile, estimate_compile, limits_from_options
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir import Graph
from ir.errors import BudgetError, CompileError, SimulationError


def _net(n_steps: int = 10) -> SpikingNetwork:
    return SpikingNetwork(
        name="n", n_steps=n_steps,
        populations=[Population(id="a", shape={"r": 5, "i": 4}, source=True),
                     Population(id="b", shape={"r": 5, "o": 2},
                                params=NeuronParams(reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                      produce=("o",), weights=np.ones((4, 2)))],
        encoders=[Encoder(port="x", population="a",
                          code=LatencyCode(t_max=n_steps, x_min=0.0, x_max=1.0))])


def test_simulation_estimate_by_hand():
    e = estimate_simulation(_net(), n_frames=3, mode="step")
    # plan: 20 B x 8 synapses + 32 B x 10 steps x 1 neuron population; per frame: state
    # 16 x 30 + neurons 24 x 10 + trains 16 x 20 + one delivery 16 x 5 reps x (4 + 2)
    # + the train's currents read ahead (step mode) 48 x 20 input spikes
    assert e.fixed_bytes == 160 + 320
    assert e.per_frame_bytes == 480 + 240 + 320 + 480 + 960
    assert e.memory_bytes == 480 + 3 * 2480
    assert estimate_simulation(_net(), n_frames=3, mode="closed").per_frame_bytes == 1520
    # step: 3 frames x (10 steps x 10 neurons / 2e8 + 40 synapse instances x 1 spike / 1e9)
    #       + 10 steps x 2 populations x 2e-5 s
    assert e.time_s == pytest.approx(3 * (100 / 2e8 + 40 / 1e9) + 20 * 2e-5)
    recorded = estimate_simulation(_net(), n_frames=3, mode="step", record_spikes=True)
    assert recorded.per_frame_bytes == e.per_frame_bytes + 10 * 30


def test_frames_are_read_from_shapes_only():
    net = _net()
    assert frames_in(net, {"x": np.zeros((5, 4))}) == 1
    assert frames_in(net, {"x": np.zeros((7, 5, 4))}) == 7
    assert frames_in(net, {"x": [[0.0]]}) == 1  # not an array: encode_inputs will say so


def test_simulate_refuses_over_the_memory_limit_before_running():
    net = _net()
    x = np.zeros((100, 5, 4))
    need = 480 + 100 * 2480  # the step engine (the network cannot run in closed form)
    with pytest.raises(SimulationError) as info:
        simulate(net, {"x": x}, max_memory_bytes=need - 1)
    message = str(info.value)
    assert "100 frames" in message and "248 kB" in message and "99 frames per call" in message
    assert simulate(net, {"x": x}, max_memory_bytes=need, out_of_range="clip").n_frames == 100
    assert simulate(net, {"x": x}, max_memory_bytes=None).n_frames == 100


def test_per_step_schedules_count_so_a_billion_steps_is_refused_before_the_plan():
    with pytest.raises(SimulationError, match=r"32 GB fixed"):
        simulate(_net(n_steps=10**9), {"x": np.zeros((5, 4))})


def test_simulate_refuses_over_the_time_limit_and_suggests_the_closed_form():
    net = _net(n_steps=10**6)
    with pytest.raises(SimulationError, match=r"mode='closed' \(about .* s\).*fewer time steps"):
        simulate(net, {"x": np.zeros((5, 4))}, mode="step", max_time_s=1.0)


def test_run_program_passes_the_limits_to_each_segment():
    g = Graph.from_dict({"nodes": [
        {"id": "a", "op": "input", "shape": {"range": 8}, "domain": "power"},
        {"id": "c", "op": "cfar", "input": "a", "kind": "ca", "guard": 0, "train": 1,
         "alpha": 1.5},
        {"id": "o", "op": "output", "input": "c"}]})
    x = {"a": np.linspace(0.1, 1.0, 8)}
    program = compile_graph(g, target=None, calibration_inputs=x)
    with pytest.raises(SimulationError, match="max_memory_bytes"):
        run_program(program, x, max_memory_bytes=10)


def _dft_chain(n: int) -> Graph:
    return Graph.from_dict({"name": "big", "nodes": [
        {"id": "x", "op": "adc_input", "shape": {"sample": n}, "complex": True},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample"},
        {"id": "o", "op": "output", "input": "f"}]})


def test_compile_estimate_by_hand():
    e = estimate_compile(_dft_chain(10))
    # x, o: 2 x 10 x 16 + 200 x 10 x 4 = 8320 each; f adds 3 x 8 x (10 x 4)(10 x 4) = 38400
    assert e.per_node == {"x": 8320, "f": 8320 + 38400, "o": 8320}
    assert e.largest == "f"
    assert e.time_s == pytest.approx(3 * 40 * 2e-6 + 1600 * 1e-8)


def test_compile_graph_refuses_a_huge_chain_before_allocating():
    graph = _dft_chain(2**20)  # a million-point complex DFT: ~ 4e13 dense weight entries
    with pytest.raises(BudgetError) as info:
        compile_graph(graph, target=None)  # would need terabytes; refused in microseconds
    assert info.value.node == "f"
    assert "max_memory_bytes" in str(info.value) and "'f': 'host'" in str(info.value)
    with pytest.raises(BudgetError, match="max_time_s"):
        check_compile(_dft_chain(256), max_memory_bytes=None, max_time_s=1e-6)


def test_limit_options_are_compile_options_with_checked_values():
    assert {"max_memory_bytes", "max_time_s"} <= set(EXTRA_OPTIONS)
    assert limits_from_options(None) == (MAX_MEMORY_BYTES, 3600.0)
    assert limits_from_options({"max_memory_bytes": None}) == (None, 3600.0)
    for bad in ({"max_memory_bytes": 0}, {"max_time_s": float("nan")},
                {"max_time_s": "1h"}, {"max_memory_bytes": True}):
        with pytest.raises(CompileError, match=next(iter(bad))):
            compile_graph(_dft_chain(4), target=None, options=bad)


BAD_LIMITS = [float("nan"), float("inf"), "x", "1h", True, -1, 0, [1]]


@pytest.mark.parametrize("name", ["max_memory_bytes", "max_time_s"])
@pytest.mark.parametrize("value", BAD_LIMITS, ids=repr)
def test_a_bad_limit_is_a_typed_error_naming_it_never_a_disabled_guard(name, value):
    x = {"x": np.full((5, 4), 0.5)}
    with pytest.raises(SimulationError, match=rf"network 'n': {name}=.* must be a positive "
                                              "finite number"):
        simulate(_net(), x, **{name: value})
    host_only = compile_graph(_dft_chain(4), target=None, motifs={"f": "host"})  # no guard ran
    with pytest.raises(SimulationError, match=rf"program 'big': {name}=.* must be a positive"):
        run_program(host_only, {"x": np.ones(4, complex)}, **{name: value})
    with pytest.raises(CompileError, match=rf"chain 'big': {name}=.* must be a positive"):
        check_compile(_dft_chain(4), **{name: value})
    with pytest.raises(CompileError, match=rf"compile option: {name}=.* must be a positive"):
        limits_from_options({name: value})


def test_raster_limit_and_input_keys_are_checked():
    x = {"x": np.full((5, 4), 0.5)}
    for value in (float("nan"), "x"):
        with pytest.raises(SimulationError, match="raster_limit_bytes=.* must be a positive"):
            simulate(_net(), x, record_spikes=True, raster_limit_bytes=value)
    program = compile_graph(_dft_chain(4), target=None, motifs={"f": "host"})
    with pytest.raises(SimulationError, match=r"input key 1 \(int\) is not an input node id"):
        run_program(program, {1: np.ones(4), "x": np.ones(4, complex)})
