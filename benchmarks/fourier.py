"""Accuracy studies of the spiking Fourier motifs; prints figures, not a test.

``python benchmarks/fourier.py [--study time-coded|rate|fft ...]`` runs the studies defined here
(all by default):

* ``time_coded_study()`` — the time-coded S-FT (motif ``time``) on the real TI chirps
  (first N samples, 4 chirps, S-FT accuracy protocol): RMSE vs T = 32 … 512 for both
  calibration policies and both charging schedules (plus the schedule ``auto`` picks);
  the spiking magnitudes' error against the true modulus; the compiled range S-FT →
  Doppler S-FT → magnitude chain on the carrada and seed003 presets.
* ``rate_study()`` / ``fft_study()`` — the rate-coded S-DFT and radix-4 S-FFT (part B).

Everything runs the closed-form engine (identical to the step engine on these networks).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from backends.reference import run_program
from compiler.chains import range_doppler_chain
from compiler.compile import calibrate_pass, lower_pass
from compiler.lowering import default_registry
from compiler.lowering.dft_common import sft_rmse
from compiler.lowering.magnitude import amb, l1
from compiler.passes import CompileContext, Verify, run_pipeline
from compiler.passes.fuse_linear import FuseLinear
from compiler.program import CompiledProgram
from ir import Graph, evaluate
from radar.config import preset
from radar.loaders import load_ti_chirps
from radar.scene import SCENE_PRESETS, simulate_frame

# ---------------------------------------------------------------------------- time-coded (A)

STEPS = (32, 64, 128, 256, 512)


def _compile(graph: Graph, calib: dict, **options) -> CompiledProgram:
    ctx = CompileContext(calibration_inputs=calib, lowering=default_registry())
    return run_pipeline([Verify(), FuseLinear(), calibrate_pass(options), lower_pass(options)], ctx,
                        CompiledProgram(graph=graph))


def _sft_graph(n: int) -> Graph:
    return Graph.from_dict({"name": f"ti-{n}", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})


def sft_rmse_table(ns=(256, 1024), steps=STEPS) -> None:
    """RMSE (the S-FT accuracy protocol) of the time-coded S-FT on the TI chirps."""
    chirps, _ = load_ti_chirps()
    print("time-coded S-FT on the TI chirps: RMSE (bins 1..N/2-1, joint min-max, mean of 4)")
    print("paper / authors' code at T=256: 0.0108 (N=256), 0.0149 (N=1024)")
    for n in ns:
        x = chirps[:, :n].astype(np.float64)
        ref = np.fft.fft(x, axis=1)[:, :n // 2]
        print(f"\nN = {n}   {'T':>6}" + "".join(f"{t:>9}" for t in steps))
        for policy in ("static", "per-input"):
            for charging in ("constant", "companding", "auto"):
                row, picked = [], []
                for t in steps:
                    p = _compile(_sft_graph(n), {"x": x}, calibration=policy, time_steps=t,
                                 charging=charging)
                    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
                    row.append(sft_rmse(y, ref, n_fft=n))
                    kind = p.networks[0].meta["charging"]["f"]["kind"]
                    picked.append("C" if kind == "constant" else "K")
                tag = f"{policy:>9} {charging:<10}"
                note = (f"  (auto picked: {''.join(picked)}; C constant, K companding)"
                        if charging == "auto" else "")
                print(f"  {tag}" + "".join(f"{v:9.5f}" for v in row) + note)


def magnitude_table() -> None:
    """Error of each magnitude motif against |z| (formula, and spiking on the TI spectra)."""
    print("\nmagnitude motifs vs the true modulus |z|")
    theta = np.linspace(0, np.pi / 2, 100001)
    z = np.exp(1j * theta)
    for name, f in (("l1", l1), ("amb", amb)):
        r = f(z)
        print(f"  {name:>4}: ratio to |z| in [{r.min():.4f}, {r.max():.4f}] over all phases")
    chirps, _ = load_ti_chirps()
    x = chirps[:, :256].astype(np.float64)
    g = Graph.from_dict({"name": "mag", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": 256}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "mag", "op": "magnitude", "input": "f", "kind": "l2"},
        {"id": "o", "op": "output", "input": "mag"}]})
    true = evaluate(g, {"x": x})["o"]
    for motif in ("host", "l1", "amb"):
        p = _compile(g, {"x": x}, time_steps=256, motifs={"mag": motif})
        y = run_program(p, {"x": x}, mode="closed").outputs["o"]
        rel = np.abs(y - true) / true.max()
        kinds = [s.kind for s in p.segments]
        print(f"  {motif:>4} (TI N=256, T=256, segments {kinds}): max |err|/max|z| = "
              f"{rel.max():.4f}, RMS = {np.sqrt(np.mean(rel ** 2)):.4f}")


def _rd_chain(name: str) -> Graph:
    d = range_doppler_chain(preset(name)).to_dict()
    d["nodes"] = [n for n in d["nodes"] if n["id"] not in ("rd", "det", "out")]
    d["nodes"].append({"id": "out", "op": "output", "input": "mag"})
    next(n for n in d["nodes"] if n["id"] == "mag")["kind"] = "l2"
    return Graph.from_dict(d)


def range_doppler_table() -> None:
    """The compiled 2D chain: where the spiking map peaks around each target."""
    print("\nrange S-FT -> Doppler S-FT -> magnitude (spiking unless 'host'): the map's peak in a"
          " 5x5 box around each target vs the conventional map's")
    for name, steps in (("carrada", (64, 128, 256)), ("seed003", (512, 2048, 4096))):
        g = _rd_chain(name)
        frame = simulate_frame(preset(name), SCENE_PRESETS[name](), seed=1)
        ref = evaluate(g, {"adc": frame.adc})["out"].sum(axis=0)
        for t in steps:
            for motif in ("host", "amb", "l1"):
                start = time.perf_counter()
                p = _compile(g, {"adc": frame.adc}, time_steps=t, motifs={"mag": motif})
                y = run_program(p, {"adc": frame.adc}, mode="closed").outputs["out"].sum(axis=0)
                secs = time.perf_counter() - start
                same = near = 0
                for tr in frame.truth:
                    box = (slice(max(tr.doppler_bin - 2, 0), tr.doppler_bin + 3),
                           slice(max(tr.range_bin - 2, 0), tr.range_bin + 3))
                    a = np.unravel_index(ref[box].argmax(), ref[box].shape)
                    b = np.unravel_index(y[box].argmax(), y[box].shape)
                    same += int(a == b)
                    near += int(np.abs(np.subtract(a, b)).max() <= 1)
                err = np.abs(y / y.max() - ref / ref.max()).max()
                print(f"  {name:>8} T={t:<5} {motif:>4}: peak bin equal {same}/{len(frame.truth)}, "
                      f"within 1 bin {near}/{len(frame.truth)}, max |normalised map error| "
                      f"{err:.4f}, {secs:.1f} s")


def time_coded_study() -> None:
    """Part A's figures: S-FT RMSE curves, magnitude errors, the 2D chain's peaks."""
    sft_rmse_table()
    magnitude_table()
    range_doppler_table()


# ---------------------------------------------------------------------------- rate / S-FFT (B)

#: Frame lengths of the rate-coded S-DFT study (the paper ran 10 000 steps).
RATE_STEPS = (100, 1000, 10000)


def _rate_graph(chirps: int, two_d: bool) -> Graph:
    nodes = [{"id": "adc", "op": "input", "shape": {"chirp": chirps, "sample": 1024}},
             {"id": "win", "op": "window", "input": "adc", "axis": "sample", "kind": "hann"},
             {"id": "rng", "op": "dft", "input": "win", "axis": "sample", "out_axis": "range",
              "keep": "positive"}]
    if two_d:
        nodes.append({"id": "dop", "op": "dft", "input": "rng", "axis": "chirp",
                      "out_axis": "doppler", "shift": True})
    nodes.append({"id": "o", "op": "output", "input": nodes[-1]["id"]})
    return Graph.from_dict({"name": "seed003-rate", "nodes": nodes})


def rate_study(steps=RATE_STEPS, chirps: int = 128) -> None:
    """Rate-coded S-DFT on the seed003 scene: modulus RMSE vs steps, 1D and 2D, time, peak RSS.

    Static calibration on another frame of the scene (seed 1); the test frame is seed 0.
    Moduli min-max normalised over all entries, positive range bins without bin 0.
    """
    import resource

    from backends.reference import simulate
    from compiler.lowering.dft_common import modulus_rmse

    cfg, scene = preset("seed003"), SCENE_PRESETS["seed003"]()
    x = simulate_frame(cfg, scene, seed=0).adc[0, :chirps]
    calib = {"adc": simulate_frame(cfg, scene, seed=1).adc[0, :chirps]}
    print(f"\nrate-coded S-DFT on seed003 ({chirps} chirps x 1024 samples, targets 5, 9, 100 m); "
          "paper: RMSE 0.0056 (1D), 0.0060 (2D) at 10 000 steps")
    print(f"{'form':>4} {'steps':>6} {'RMSE':>8} {'limit':>7} {'sim s':>7} {'peak RSS GB':>11}")
    for two_d, limit in ((False, 0.0056), (True, 0.0060)):
        g = _rate_graph(chirps, two_d)
        out = "dop" if two_d else "rng"
        ref = evaluate(g, {"adc": x})[out]
        for n in steps:
            program = _compile(g, calib, motifs={"dft": "rate"}, time_steps=n)
            (net,) = program.networks
            start = time.perf_counter()
            y = simulate(net, {"adc": x}, out_of_range="clip").outputs[out]  # not calib frame
            wall = time.perf_counter() - start
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
            print(f"{'2D' if two_d else '1D':>4} {n:>6} {modulus_rmse(y, ref):>8.5f} {limit:>7} "
                  f"{wall:>7.1f} {rss:>11.2f}")


def fft_study(ns=(256, 512, 1024), steps=(100, 256)) -> None:
    """Radix-4 S-FFT: Table 3 row, compiled counters, RMSE vs the dense S-FT on the TI chirps."""
    from backends.reference import simulate
    from compiler.lowering.dft_fft import radix_plan, sfft_resources

    est = sfft_resources(512, 100)
    print(f"\nS-FFT resources, N=512, T=100 (L = log4 N = {est.n_layers}): estimate "
          f"{est.neurons} neurons, {est.synapses} synapses, {est.steps} steps "
          "(Vogginger et al. 2022 Table 3: 4 608, 37 888, 550)")
    chirps, _ = load_ti_chirps()
    for n in ns:
        g = Graph.from_dict({"name": f"ti-{n}", "nodes": [
            {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": n}},
            {"id": "f", "op": "dft", "input": "x", "axis": "sample"},
            {"id": "o", "op": "output", "input": "f"}]})
        x = chirps[:, :n]
        net = _compile(g, {"x": x}, motifs={"dft": "time-fft"}, time_steps=100).networks[0]
        layers = [p for p in net.populations if not p.source and not p.id.endswith("clock")]
        butterflies = [p.n_synapses for p in net.projections if "/w" in p.id]
        offsets = sum(p.n_synapses for p in net.projections if "/clock" in p.id)
        e = sfft_resources(n, 100)
        neurons = sum(p.size for p in layers) // 4
        print(f"N={n} radices {radix_plan(n)}: compiled per instance {neurons} neurons (+1 clock),"
              f" {sum(butterflies)} butterfly synapses (per layer "
              f"{butterflies}, limit 16N = {16 * n}) + {offsets} offset synapses, {net.n_steps} "
              f"steps; estimate {e.neurons}, {e.synapses}, {e.steps}")
    print("TI chirps, the S-FT protocol, static calibration over the 4 chirps (closed form):")
    print(f"{'N':>5} {'T':>4} {'S-FFT':>8} {'dense same code':>15} {'ratio':>6} "
          f"{'time motif':>10} {'closed==step':>12}")
    for n in ns:
        g = Graph.from_dict({"name": f"ti-{n}", "nodes": [
            {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": n}},
            {"id": "f", "op": "dft", "input": "x", "axis": "sample"},
            {"id": "o", "op": "output", "input": "f"}]})
        x = chirps[:, :n]
        ref = evaluate(g, {"x": x})["f"]
        for t in steps:
            row = {}
            for name, opts in (("fft", {"motifs": {"dft": "time-fft"}}),
                               ("dense", {"motifs": {"dft": "time-fft"}, "fft_radices": [n]}),
                               ("time", {"motifs": {"dft": "time"}})):
                net = _compile(g, {"x": x}, time_steps=t, **opts).networks[0]
                out = simulate(net, {"x": x}, mode="closed").outputs["f"]
                row[name] = sft_rmse(out, ref)
                if name == "fft":
                    step = simulate(net, {"x": x}, mode="step").outputs["f"]
                    row["same"] = bool(np.array_equal(step, out))
            print(f"{n:>5} {t:>4} {row['fft']:>8.5f} {row['dense']:>15.5f} "
                  f"{row['fft'] / row['dense']:>6.2f} {row['time']:>10.5f} {str(row['same']):>12}")


# ---------------------------------------------------------------------------- main


STUDIES = {"time-coded": time_coded_study, "rate": rate_study, "fft": fft_study}


def main(argv: list[str] | None = None) -> None:
    """Run the studies named by ``--study`` (every study by default)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", action="append", choices=list(STUDIES),
                        help="a study to run (repeatable; default: all, the rate study is long)")
    for name in parser.parse_args(argv).study or list(STUDIES):
        STUDIES[name]()


if __name__ == "__main__":
    main()
