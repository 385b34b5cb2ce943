"""The carrada range-Doppler-CFAR chain and the ``emit`` command, end to end."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from backends.artifact import save
from backends.emit.run_package import run_package
from backends.reference import run_program, simulate
from compiler.chains import range_doppler_chain
from compiler.compile import compile_graph
from radar.config import RadarConfig, preset
from radar.scene import SCENE_PRESETS, simulate_frame
from radarsnn.cli.emit import add_parsers, run_emit


def test_carrada_chain_matches_the_reference_step_for_step(tmp_path):
    """The carrada preset with 16 chirps and one transmitter (1/8 of the cube, to keep
    the test near 10 s; the full cube matches too, see docs/emit.md)."""
    from backends.emit import emit_numpy

    cfg = RadarConfig(**{**preset("carrada").model_dump(), "n_chirps": 16,
                         "tx_positions_lambda": (0.0,)})
    adc = simulate_frame(cfg, SCENE_PRESETS["carrada"](), seed=1).adc
    # calibrated on the frame it runs: every input inside the encoders' ranges
    program = compile_graph(range_doppler_chain(cfg), calibration_inputs={"adc": adc})
    assert [s.kind for s in program.segments].count("spiking") == 2
    ref = run_program(program, {"adc": adc}, mode="step")
    out, counts = run_package(emit_numpy(program, tmp_path), {"adc": adc})
    np.testing.assert_array_equal(out["out"], ref.outputs["out"])
    assert out["out"].any()
    assert counts == [s.spike_counts for s in ref.simulations]


def _tiny_network():
    from compiler.snn import (
        Decoder,
        Encoder,
        LatencyCode,
        MatrixProjection,
        NeuronParams,
        Population,
        SpikingNetwork,
    )
    return SpikingNetwork(
        name="tiny", n_steps=6,
        populations=[Population(id="in", shape={"i": 2}, source=True),
                     Population(id="out", shape={"o": 1},
                                params=NeuronParams(du=0.0, v_th=3.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1)))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="out", kind="spike_time", scale=-1.0)])


def test_emit_command_on_an_artifact_and_a_chain_file(tmp_path, capsys):
    net = _tiny_network()
    artifact = save(net, tmp_path / "artifact")
    parser = argparse.ArgumentParser(prog="radarsnn")
    add_parsers(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["emit", str(artifact), "-o", str(tmp_path / "out"),
                              "--name", "tiny_pkg"])
    assert args.func(args) == 0
    pkg = tmp_path / "out" / "tiny_pkg"
    assert capsys.readouterr().out.strip() == str(pkg)
    x = np.array([1.0, 0.5])
    out, counts = run_package(pkg, {"x": x})
    ref = simulate(net, {"x": x}, mode="step")
    assert out["t"].tolist() == ref.outputs["t"].tolist() == [2.0]
    assert counts == [ref.spike_counts]

    chain = tmp_path / "chain.yaml"
    chain.write_text("name: tiny-dft\nnodes:\n"
                     "  - {id: x, op: input, shape: {sample: 8}}\n"
                     "  - {id: f, op: dft, input: x, axis: sample, keep: positive}\n"
                     "  - {id: o, op: output, input: f}\n")
    pkg = run_emit(chain, tmp_path / "gen", target="unbounded", time_steps=32)
    assert pkg.name == "snn_tiny_dft" and (pkg / "network_0.py").is_file()
    x = np.random.default_rng(0).normal(size=8)
    out, _ = run_package(pkg, {"x": x})
    assert out["o"].shape == (4,) and np.iscomplexobj(out["o"])


def test_emit_command_on_a_compiled_program_folder(tmp_path, capsys):
    """Issue 19 item 2: ``radarsnn emit build/ti -o build/generated`` (a program, not a network)."""
    from backends import load_program, save_program
    from ir import Graph

    graph = Graph.from_yaml(
        "name: tiny-dft\nnodes:\n  - {id: x, op: input, shape: {sample: 8}}\n"
        "  - {id: f, op: dft, input: x, axis: sample, keep: positive}\n"
        "  - {id: o, op: output, input: f}\n")
    x = np.random.default_rng(1).normal(size=8)
    program = compile_graph(graph, "unbounded", time_steps=32,
                            calibration_inputs={"x": np.random.default_rng(2).normal(size=8)})
    folder = save_program(program, tmp_path / "build" / "ti")
    parser = argparse.ArgumentParser(prog="radarsnn")
    add_parsers(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["emit", str(folder), "-o", str(tmp_path / "gen")])
    assert args.func(args) == 0
    pkg = Path(capsys.readouterr().out.strip())
    out, _ = run_package(pkg, {"x": x})
    ref = run_program(load_program(folder), {"x": x}, mode="step", out_of_range="clip")
    np.testing.assert_array_equal(out["o"], ref.outputs["o"])
