"""Calibration that transfers to new frames (issue: chip dynamic range, item 3).

* a **guard** on host-decoded S-FT outputs: values above the calibrated full scale are
  coded coarsely instead of clipped (the TI chirps, calibrated on the other three: one
  peaks 5.5× above any of them);
* **dithered input rounding** where a later stage sums over another axis and the
  measured repeated rounding error would add up coherently (static signal over chirps);
* the **ADC full scale** as the bound of a compile without calibration data (warned).
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.hardware import load_profile
from compiler.lowering.charging import constant_schedule, with_guard
from compiler.lowering.dft_common import sft_rmse
from compiler.lowering.time_inputs import repeated_rounding_error
from compiler.passes.calibrate import CalibrationWarning
from compiler.snn.coding import LatencyCode, dither_offsets
from ir import Graph, evaluate
from radar.loaders import load_ti_chirps


def _range_graph(n: int) -> Graph:
    return Graph.from_dict({"name": "ti-range", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})


def test_a_guard_keeps_the_body_and_codes_values_above_it_within_its_step() -> None:
    body = constant_schedule(240, v_full=240.0)
    guarded = with_guard(body, 16, ratio=16.0)
    v = np.linspace(0.0, 240.0, 997)
    np.testing.assert_array_equal(guarded.decode(v), body.decode(v))  # the body is unchanged
    high = np.geomspace(241.0, 16 * 240.0, 500)
    rel = np.abs(guarded.decode(high) - high) / high
    assert rel.max() <= (16 ** (1 / 16) - 1) / 2 + 1e-3  # ±9 %
    assert np.all(body.decode(high) == body.levels()[0])  # without the guard: clipped


def test_ti_chirp_calibrated_on_the_other_three_is_not_clipped(shared_data) -> None:
    """Chirp 0's spectrum peaks 5.6× above any calibration chirp's (RMSE 0.23 before).

    Every second sample of the chirps (512 of 1 024): the same spectrum folded once, whose
    peaks stand as far apart (5.56× here, 5.52× on all samples; RMSE 0.0009 with the guard
    and 0.23 without, 0.0018 and 0.23 on all), at about half the CPU time.
    """
    x, _ = load_ti_chirps(shared_data)
    x = x[:, ::2].astype(np.float64)
    n = x.shape[1]
    program = compile_graph(_range_graph(n), load_profile("loihi2"),
                            calibration_inputs={"x": x[1:]}, time_steps=256,
                            options={"output_spikes": "time"})  # the charging stage's guard
    meta = program.networks[0].meta["charging"]["f"]
    assert meta["guard"]["ratio"] >= 8 and meta["guard"]["steps"] == 16
    y = run_program(program, {"x": x[0]}, out_of_range="clip").outputs["o"]
    rmse = sft_rmse(y[None], np.fft.fft(x[0])[None, : n // 2], n_fft=n)
    assert rmse <= 0.0149, rmse
    off = compile_graph(_range_graph(n), load_profile("loihi2"), calibration_inputs={"x": x[1:]},
                        time_steps=256, options={"charging_guard": 1, "output_spikes": "time"})
    y_off = run_program(off, {"x": x[0]}, out_of_range="clip").outputs["o"]
    assert sft_rmse(y_off[None], np.fft.fft(x[0])[None, : n // 2], n_fft=n) > 5 * rmse


def test_dither_offsets_are_uniform_and_fixed() -> None:
    u = dither_offsets(1 << 16)
    assert u.min() >= 0 and u.max() < 1
    counts = np.histogram(u, bins=16, range=(0, 1))[0]
    assert counts.min() > 0.9 * (1 << 12) and counts.max() < 1.1 * (1 << 12)
    assert abs(np.corrcoef(u[:-1], u[1:])[0, 1]) < 0.02
    np.testing.assert_array_equal(dither_offsets(8), dither_offsets(1 << 16)[:8])


def test_dithered_rounding_is_unbiased_where_nearest_repeats_its_error() -> None:
    code = {r: LatencyCode(t_max=64, x_min=0.0, x_max=64.0, rounding=r)
            for r in ("nearest", "dither")}
    x = np.full((1, 4096), 10.3)  # one value at many positions (a static part over chirps)
    decoded = {r: c.value_of(c.spike_steps(x)) for r, c in code.items()}
    assert abs(decoded["nearest"].mean() - 10.3) == pytest.approx(0.3)
    assert abs(decoded["dither"].mean() - 10.3) < 0.02
    assert np.all(np.abs(decoded["dither"] - 10.3) < 1.0)


def _static_chain(n_chirps: int = 32, n_samples: int = 32) -> Graph:
    return Graph.from_dict({"name": "static", "nodes": [
        {"id": "adc", "op": "adc_input", "shape": {"chirp": n_chirps, "sample": n_samples}},
        {"id": "rng", "op": "dft", "input": "adc", "axis": "sample", "out_axis": "range",
         "keep": "positive"},
        {"id": "dop", "op": "dft", "input": "rng", "axis": "chirp", "out_axis": "doppler"},
        {"id": "o", "op": "output", "input": "dop"}]})


def _frames(noise: float, n: int, seed: int) -> np.ndarray:
    """ADC codes: a static tone (the same in every chirp) plus noise, on the integer grid."""
    rng = np.random.default_rng(seed)
    tone = 40.0 * np.cos(2 * np.pi * 5 * np.arange(32) / 32)
    return np.rint(tone + noise * rng.normal(size=(n, 32, 32)))


@pytest.mark.parametrize(("noise", "want"), [(0.3, "dither"), (20.0, "nearest")])
def test_input_rounding_is_measured_on_the_calibration_frames(noise: float, want: str) -> None:
    cal = _frames(noise, 2, seed=1)
    program = compile_graph(_static_chain(), "loihi2", calibration_inputs={"adc": cal},
                            time_steps=48, options={"static_split": "off"})
    (enc,) = [e for net in program.networks for e in net.encoders if e.port == "adc"]
    assert enc.code.rounding == want
    s = enc.code.x_max / enc.code.t_max
    parts = np.stack([np.maximum(cal, 0), np.maximum(-cal, 0)], axis=-1)
    err = s * np.rint(parts / s) - parts
    rho = float(np.mean(err.mean(axis=1) ** 2) / (s * s / (6 * 32)))
    assert rho == pytest.approx(repeated_rounding_error(cal, s, (1,), "signed"))
    assert (rho > 1) == (want == "dither")


def test_dither_removes_the_zero_doppler_spur_of_a_static_signal() -> None:
    cal, frame = _frames(0.3, 2, seed=1), _frames(0.3, 1, seed=7)[0]
    ref = evaluate(_static_chain(), {"adc": frame})["dop"]
    spur = {}
    for mode in ("nearest", "dither"):
        program = compile_graph(_static_chain(), "loihi2", calibration_inputs={"adc": cal},
                                time_steps=48,
                                options={"input_rounding": mode, "static_split": "off"})
        y = run_program(program, {"adc": frame}, out_of_range="clip").outputs["o"]
        err = np.abs(y - ref)
        spur[mode] = float(err[0].max() / np.median(err[1:]))  # zero Doppler vs the others
    assert spur["nearest"] > 3 * spur["dither"], spur


def test_without_calibration_data_the_adc_full_scale_bounds_every_stage() -> None:
    d = _static_chain().to_dict()
    d["nodes"][0]["full_scale"] = 2048.0
    graph = Graph.from_dict(d)
    with pytest.warns(CalibrationWarning, match=r"ADC full scale of 'adc' \(2048\)"):
        program = compile_graph(graph, "loihi2", time_steps=48)
    cal = program.records["calibrate"]
    assert cal.source == "bounds" and cal.nodes["adc"].max_part == 2048.0
    full = np.full((32, 32), 2047.0)  # a full-scale frame is never out of range
    result = run_program(program, {"adc": full})
    assert not result.clipped


def test_per_input_values_come_back_in_the_inputs_units(tmp_path) -> None:
    """Amplitude (DFT), power (|x|²) and dB values of a per-input program are physical; the
    generated package undoes the same peaks (bit for bit)."""
    import importlib
    import sys

    from backends.emit import emit_numpy

    graph = Graph.from_dict({"name": "units", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 3, "sample": 32}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "p", "op": "magnitude", "input": "f", "kind": "square"},
        {"id": "db", "op": "log", "input": "p"},
        {"id": "of", "op": "output", "input": "f"},
        {"id": "op", "op": "output", "input": "p"},
        {"id": "odb", "op": "output", "input": "db"}]})
    rng = np.random.default_rng(3)
    n = np.arange(32)
    x = np.cos(2 * np.pi * 5 * n / 32)[None] * np.array([[1.0], [30.0], [900.0]])
    x = x + 0.01 * rng.normal(size=x.shape)
    program = compile_graph(graph, calibration="per-input", calibration_inputs={"x": x / 7},
                            time_steps=128)
    result = run_program(program, {"x": x})
    want = evaluate(graph, {"x": x})
    peak = np.abs(want["f"]).max(axis=1, keepdims=True)
    assert np.abs(result.outputs["of"] - want["f"]).max(axis=1, keepdims=True).max() > 0
    assert np.all(np.abs(result.outputs["of"] - want["f"]) <= 0.02 * peak)  # each chirp's own
    np.testing.assert_allclose(result.outputs["op"].max(axis=1), want["p"].max(axis=1),
                               rtol=0.05)
    np.testing.assert_allclose(result.outputs["odb"].max(axis=1), want["db"].max(axis=1),
                               atol=0.3)
    assert result.normalized == [] and result.input_peaks["x"].shape == (3, 1)
    sys.path.insert(0, str(tmp_path))
    try:
        pkg = importlib.import_module(emit_numpy(program, tmp_path, name="units_pkg").name)
        got = pkg.run({"x": x})
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("units_pkg", None)
    for k in ("of", "op", "odb"):
        np.testing.assert_array_equal(got[k], result.outputs[k])


@pytest.mark.parametrize(("option", "value", "what"), [
    ("static_split", "on", "auto or off"),
    ("input_rounding", "round", "auto, nearest or dither"),
    ("charging_guard", 0.5, r"a finite number >= 1 \(1: no guard\)"),
    ("charging_guard", float("nan"), "a finite number >= 1"),
    ("encoder_headroom", 0.5, r"auto or a number in 1\.\.2\^62"),
])
def test_the_typed_options_are_refused_before_any_pass_runs(option, value, what) -> None:
    from ir.errors import CompileError

    with pytest.raises(CompileError, match=rf"compile option {option}=.* must be {what}"):
        compile_graph(_range_graph(16), None, options={option: value})


def test_the_encoder_range_leaves_the_calibration_sets_spread_at_least_6_db() -> None:
    rng = np.random.default_rng(5)
    one = rng.normal(size=(1, 16))
    def x_max(cal, **options):
        p = compile_graph(_range_graph(16), None, calibration_inputs={"x": cal}, time_steps=32,
                          options=options)
        (enc,) = p.networks[0].encoders
        return enc.code.x_max
    top = float(np.abs(one).max())
    assert x_max(one) == pytest.approx(2 * top)  # one frame: the 6 dB minimum
    assert x_max(one, encoder_headroom=1) == pytest.approx(top)
    spread = np.stack([one[0], 5 * one[0], one[0]])  # peaks 1, 5, 1 (x top): median 1
    assert x_max(spread) == pytest.approx(5 * 5 * top)
