"""``radarsnn bench`` runs and reports its figures (timings are not asserted: benchmarks/)."""

from __future__ import annotations

import json

from radarsnn.bench import BenchReport, run_bench
from radarsnn.cli import main


def test_bench_times_the_closed_form_against_numpy_and_its_floor():
    report = run_bench("seed003", repeats=1, modes=("closed",), brian2=False, user_path=False)
    assert set(report.seconds) == {"conventional", "closed", "floor", "floor_core"}
    ratios = report.ratios()
    assert ratios["closed_over_conventional"] > 0 and ratios["closed_over_floor"] > 0
    text = report.to_text()
    assert "closed_over_floor" in text and "load average" in text and report.peak_rss_gb > 0
    assert report.floor_products and len(report.load_before) == 3


def test_the_floor_is_the_silent_stages_dense_products():
    """The range and Doppler S-FT matrices, one row per frame x repetition, shared (no copy)."""
    from backends.reference import build_plan
    from backends.reference.floor import floor_products
    from compiler.chains import range_doppler_chain
    from compiler.compile import compile_graph
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame

    config = preset("seed003")
    frame = simulate_frame(config, SCENE_PRESETS["seed003"](), seed=1).adc
    program = compile_graph(range_doppler_chain(config), None, calibration_inputs={"adc": frame})
    plans = [build_plan(net) for net in program.networks]
    products = floor_products(plans)
    rx, chirps, samples = frame.shape
    assert [p.shape[0] for p in products] == [rx * chirps, rx * samples // 2]
    dl = plans[0].deliveries[products[0].id]
    assert products[0].weights is dl.weights[0]


def test_chain_inputs_refuses_a_chain_larger_than_the_frame():
    import numpy as np
    import pytest

    from ir import Graph
    from ir.errors import RadarConfigError
    from radarsnn.bench import chain_inputs

    g = Graph.from_dict({"name": "g", "nodes": [
        {"id": "adc", "op": "adc_input", "shape": {"rx": 9, "sample": 4}, "complex": True},
        {"id": "out", "op": "output", "input": "adc"}]})
    with pytest.raises(RadarConfigError, match="does not fit inside"):
        chain_inputs(g, np.zeros((8, 16), complex))


def test_ratios_are_computed_from_one_run():
    r = BenchReport(preset="p", repeats=1, threads=1, machine="m",
                    seconds={"conventional": 0.1, "closed": 0.5, "closed_range_stage": 0.01,
                             "step_range_stage": 0.1, "brian2_range_stage": 2.0})
    assert r.ratios() == {"closed_over_conventional": 5.0,
                          "brian2_over_closed_range_stage": 200.0,
                          "brian2_over_step_range_stage": 20.0}
    assert r.frames_per_s["closed"] == 2.0


def test_bench_cli_json(capsys):
    assert main(["bench", "--preset", "seed003", "--repeats", "1", "--mode", "closed",
                 "--no-brian2", "--no-user-path", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["preset"] == "seed003" and "closed" in doc["frames_per_s"]
    assert {"floor", "floor_core"} <= set(doc["seconds"]) and "closed_over_floor" in doc["ratios"]
    assert len(doc["load_before"]) == 3 and doc["cpu_count"] >= 1
    # every stage's CPU, and the whole process's, each with its system / user
    phases = doc["cpu_phases"]
    assert set(phases) == {"compile", "conventional", "closed (with its floor)", "process"}
    assert all(set(v) == {"user_s", "system_s"} for v in phases.values())
    assert all(v["user_s"] >= 0 and v["system_s"] >= 0 for v in phases.values())
    assert phases["process"]["user_s"] >= sum(v["user_s"] for k, v in phases.items()
                                              if k != "process")
    assert set(doc["system_over_user_by_phase"]) <= set(phases)


def test_bench_motif_resonator_times_the_resonator_chain_against_its_rotations(capsys):
    assert main(["bench", "--preset", "seed003", "--motif", "resonator", "--repeats", "1",
                 "--mode", "closed", "--no-brian2", "--no-user-path", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["motif"] == "resonator" and "resonator" in doc["chain"]
    assert set(doc["seconds"]) == {"conventional", "closed", "floor", "floor_core"}
    assert doc["ratios"]["closed_over_floor"] > 0
    # the floor is the fixed-point rotations of the range and Doppler resonators
    assert [p.split()[0] for p in doc["floor_products"]] == ["rng__moving/out",
                                                            "dop__moving/out"]
    assert all("12-bit rotations" in p for p in doc["floor_products"])


def test_bench_refuses_an_unknown_motif():
    import pytest

    from ir.errors import CompileError

    with pytest.raises(CompileError, match="not one of"):
        run_bench("seed003", repeats=1, modes=("closed",), brian2=False, motif="fft")
