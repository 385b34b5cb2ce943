"""Chip-faithful accuracy: the compiled range-Doppler-CFAR chain vs the conventional one.

``python benchmarks/chip_accuracy.py [--quick] [--targets loihi2,...] [--out FILE.md]``
``python benchmarks/chip_accuracy.py --case leaky_mimo --target loihi2 [--motifs dft=resonator]``

For each hardware profile (loihi2, loihi, spinnaker2, unbounded) the chain is compiled
**calibrated on frames of other seeds** (seeds 100 and 101, never measured) and run on:

* the ``carrada`` and ``seed003`` preset scenes, seeds 0–4: cell sensitivity / precision
  of the spiking detections against the conventional ones (|S ∩ C|/|C|, |S ∩ C|/|S|), the
  ground-truth targets found (± 1 bin) and the false objects (detection peaks matching no
  target, clutter or leakage) of both chains;
* ``carrada`` scenes with one target 30, 45 and 60 dB below the strongest return (the
  fast car): does the spiking chain find what the conventional chain finds?
* the real TI chirps (``radar/data/ti_chirps``): the range S-FT at T = 256, calibrated on
  the *other* three chirps (leave one out), RMSE of the S-FT accuracy protocol;
* the two real OpenRadar TI captures (``radar/data/openradar``), each calibrated on the
  other: cell sensitivity / precision of a range–Doppler OS-CFAR chain.

and the hard cases of :data:`radarsnn.demo.hard_cases.HARD_CASES` (``--case`` picks some and
skips the rows above): scenes of :mod:`radar.scene_cases` drawn afresh per seed, calibrated
on seeds 100–101, measured on seeds 0–2 (``--seeds``): leakage 40–70 dB above the targets
on a 3 Tx × 4 Rx 12-bit sensor, a clipping ADC, targets near the noise threshold, range
migration, CA-CFAR on linear power, a 1-D chirp sequence (range + CFAR per chirp).
``--motifs node=motif,...`` compiles every chain with those motifs; ``--json FILE`` writes
the hard cases' totals.

It prints the tables and writes them, with the command and the machine, to ``--out``.
Everything runs the closed-form engine (identical to the step engine on these networks).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

from backends.reference import run_program
from compiler.chains import capture_chain, range_doppler_chain
from compiler.compile import compile_graph
from compiler.hardware import load_profile
from compiler.lowering.dft_common import sft_rmse
from ir import Graph, evaluate
from ir.errors import CompileError
from radar.config import preset
from radar.loaders import load_openradar, load_ti_chirps
from radar.scene import SCENE_PRESETS, Target, simulate_frame
from radar.scene_cases import SCENE_CASES
from radarsnn.demo.hard_cases import HARD_CASES, CaseScore, compile_for, measure_case
from radarsnn.demo.matching import score_peaks

TARGETS = ("loihi2", "loihi", "spinnaker2", "unbounded")
CALIBRATION_SEEDS = (100, 101)
#: The calibration seed the measured compile (``--auto``) holds back for its contract.
HELD_BACK_SEED = 102


def _rd(values: dict, graph: Graph, node: str) -> np.ndarray:
    axes = list(graph.infer_types()[node].axes)
    return np.asarray(values[node]).transpose([axes.index("range"), axes.index("doppler")])


#: Notes on targets that needed a board instead of one chip (filled by ``_compile``).
BOARDS: dict[str, str] = {}


def _profile(target: str):
    return None if target == "unbounded" else load_profile(target)


def _compile(name: str, scene, target: str, motifs: dict[str, str], measured: bool = False):
    """Compile on ``target``; a chain that does not fit one chip is placed on a board of
    as many chips as it needs (accuracy does not depend on the placement; noted).
    ``measured``: the measured compile, its contract on the held-back seed 102."""
    config = preset(name)
    graph = range_doppler_chain(config)
    seeds = (*CALIBRATION_SEEDS, HELD_BACK_SEED) if measured else CALIBRATION_SEEDS
    cal = np.stack([simulate_frame(config, scene, seed=s).adc for s in seeds])
    program, note = compile_for(graph, target, {"adc": cal}, motifs=motifs, measured=measured)
    if note:
        BOARDS[f"{target}/{name}"] = f"{name} {note}"
    return config, graph, program


def scene_rows(name: str, target: str, seeds, scene=None, motifs: dict[str, str] | None = None,
               measured: bool = False) -> dict:
    """Totals over ``seeds`` of one preset's scene (or a given scene) on one target."""
    scene = scene or SCENE_PRESETS[name]()
    config, graph, program = _compile(name, scene, target, motifs or {}, measured)
    tot = dict(conv=0, spk=0, hits=0, truth=0, conv_found=0, spk_found=0, conv_false=0,
               spk_false=0, clipped=0, frames=0)
    for seed in seeds:
        frame = simulate_frame(config, scene, seed=seed)
        conv = evaluate(graph, {"adc": frame.adc})
        res = run_program(program, {"adc": frame.adc}, mode="auto", out_of_range="clip")
        c = _rd(conv, graph, "det")
        s = _rd(res.values, program.graph, "det").astype(bool)
        truth = [(int(t.range_bin), int(t.doppler_bin)) for t in frame.truth]
        cs = score_peaks(c, _rd(conv, graph, "rd"), truth)
        ss = score_peaks(s, _rd(res.values, program.graph, "rd"), truth)
        tot["conv"] += int(c.sum())
        tot["spk"] += int(s.sum())
        tot["hits"] += int((s & c).sum())
        tot["truth"] += len(truth)
        tot["conv_found"] += sum(f is not None for f in cs.found)
        tot["spk_found"] += sum(f is not None and g is not None
                                for f, g in zip(cs.found, ss.found, strict=True))
        tot["conv_false"] += cs.n_false
        tot["spk_false"] += ss.n_false
        tot["clipped"] += int(sum(res.clipped.values()))
        tot["frames"] += 1
    return tot


def dynamic_range_scene(below_db: float):
    """carrada with the pedestrian ``below_db`` under the strongest target's return."""
    base = SCENE_PRESETS["carrada"]()
    strongest = max(base.targets, key=lambda t: t.rcs_dbsm - 40 * np.log10(t.range_m))
    level = strongest.rcs_dbsm - 40 * np.log10(strongest.range_m) - below_db
    weak = Target(range_m=30.0, velocity_mps=-6.0, azimuth_deg=5.0,
                  rcs_dbsm=float(level + 40 * np.log10(30.0)), name=f"weak_{below_db:g}dB")
    return base.model_copy(update={"targets": (*base.targets, weak),
                                   "name": f"carrada-weak{below_db:g}"})


def ti_rmse(target: str, t_steps: int = 256, motifs: dict[str, str] | None = None
            ) -> float | None:
    """Leave-one-chirp-out RMSE of the range S-FT on the TI chirps (None: no data)."""
    try:
        chirps, _ = load_ti_chirps()
    except Exception:  # noqa: BLE001 - the captures are optional here
        return None
    n = chirps.shape[1]
    graph = Graph.from_dict({"name": "ti-range", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})
    errors = []
    for i in range(chirps.shape[0]):
        others = np.delete(chirps, i, axis=0)
        program = compile_graph(graph, _profile(target), calibration_inputs={"x": others},
                                time_steps=t_steps, motifs=motifs)
        y = run_program(program, {"x": chirps[i]}, mode="auto",
                        out_of_range="clip").outputs["o"]
        ref = np.fft.fft(chirps[i])[: n // 2]
        errors.append(sft_rmse(y[None], ref[None], n_fft=n))
    return float(np.mean(errors))


def openradar_rows(target: str, motifs: dict[str, str] | None = None) -> dict | None:
    """The OpenRadar captures (same TI sensor), each calibrated on the other (first 128
    samples of ``doppler_example``): cell totals of the range–Doppler OS-CFAR chain of
    ``tests/test_real_captures.py``; None without the data."""
    try:
        frames = [load_openradar("simple_frame_1"), load_openradar("doppler_example")[:, :128]]
    except Exception:  # noqa: BLE001 - the captures are optional here
        return None
    graph = capture_chain()
    tot = dict(conv=0, spk=0, hits=0, clipped=0)
    for cal, test in ((frames[1], frames[0]), (frames[0], frames[1])):
        program = compile_graph(graph, _profile(target), calibration_inputs={"frame": cal},
                                motifs=motifs)
        conv = evaluate(graph, {"frame": test})["det"]
        res = run_program(program, {"frame": test}, mode="auto", out_of_range="clip")
        spk = np.asarray(res.values["det"]).astype(bool)
        tot["conv"] += int(conv.sum())
        tot["spk"] += int(spk.sum())
        tot["hits"] += int((conv & spk).sum())
        tot["clipped"] += int(sum(res.clipped.values()))
    return tot


def _refused(err: CompileError) -> str:
    """A table cell for a compile the target refuses: the node and what it lacks."""
    text = " ".join(str(err).split())
    if ", which the stock neurons of " in text:  # the motif needs a missing neuron feature
        head = text.split(", which the stock neurons of ")[0]
        head = re.sub(r"\s*\([^()]*\)", "", head)  # the details in brackets
        return "refused: " + re.sub(r": [^:]*?(?= and |$)", "", head)
    return "does not fit: " + text[:160]


def _ratio(a: int, b: int) -> str:
    return f"{a / b:.3f}" if b else "–"


def _motifs(text: str) -> dict[str, str]:
    """``"dft=resonator,det=host"`` -> ``{"dft": "resonator", "det": "host"}``."""
    out = {}
    for item in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise SystemExit(f"--motifs: {item!r} is not node=motif (e.g. dft=resonator)")
        out[key.strip()] = value.strip()
    return out


def preset_rows(target: str, seeds: range, quick: bool, motifs: dict[str, str],
                measured: bool = False) -> list[str]:
    """The rows of the preset scenes, the dynamic-range scenes and the real captures
    (``measured``: the scenes compiled as ``radarsnn.compile_graph`` does by default)."""
    rows = []
    cases = [(f"{n}, seeds {seeds.start}-{seeds.stop - 1}", n, None) for n in
             ("carrada", "seed003")]
    cases += [(f"carrada + target {db} dB below the strongest", "carrada",
               dynamic_range_scene(db)) for db in (30, 45, 60)]
    for label, name, scene in cases:
        try:
            t = scene_rows(name, target, seeds if scene is None else range(2), scene, motifs,
                           measured)
        except CompileError as err:  # a motif the chip's stock neurons cannot run: say so
            rows.append(f"| {target} | {label} | {_refused(err)} | | | | |")
            print(rows[-1], flush=True)
            continue
        rows.append(f"| {target} | {label} | {_ratio(t['hits'], t['conv'])} | "
                    f"{_ratio(t['hits'], t['spk'])} | {t['conv_found']}/{t['truth']} / "
                    f"{t['spk_found']}/{t['truth']} | {t['conv_false']} / {t['spk_false']} | "
                    f"{t['clipped']} |")
        print(rows[-1], flush=True)
    if quick:
        return rows
    try:
        real = openradar_rows(target, motifs)
    except CompileError as err:
        real = None
        rows.append(f"| {target} | OpenRadar TI captures, each calibrated on the other | "
                    f"{_refused(err)} | | | | |")
        print(rows[-1], flush=True)
    if real is not None:
        rows.append(f"| {target} | OpenRadar TI captures, each calibrated on the other | "
                    f"{_ratio(real['hits'], real['conv'])} | "
                    f"{_ratio(real['hits'], real['spk'])} | | | {real['clipped']} |")
        print(rows[-1], flush=True)
    try:
        rmse = ti_rmse(target, motifs=motifs)
        cell = f"RMSE {'–' if rmse is None else f'{rmse:.4f}'}"
    except CompileError as err:  # the chip cannot hold it or run it: say so, do not stop
        cell = _refused(err)
    rows.append(f"| {target} | TI chirps, range S-FT T=256, leave-one-out | {cell} | | | | |")
    print(rows[-1], flush=True)
    return rows


HARD_HEADER = [
    "| target | case | motifs | cell sensitivity | cell precision | targets found (conv / "
    "spiking) | firm targets missed | false objects per frame (conv / spiking) | clipped inputs "
    "| ADC clipped rails | compile + run s |",
    "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]


def hard_row(score: CaseScore) -> str:
    """One table row of a hard case (``profile`` cases count (target, chirp) pairs)."""
    d = score.as_dict()
    ratio = lambda v: "–" if v is None else f"{v:.3f}"  # noqa: E731
    motifs = ", ".join(f"{k}={v}" for k, v in score.motifs.items()) or "defaults"
    note = f" ({'; '.join(score.notes)})" if score.notes else ""
    return (f"| {score.target} | {score.case}{note} | {motifs} | {ratio(score.sensitivity)} | "
            f"{ratio(score.precision)} | {score.conv_found}/{score.truth} / "
            f"{score.spk_found}/{score.truth} | {score.firm_missed} of {score.firm_found} | "
            f"{d['conv_false_per_frame']:.1f} / "
            f"{d['spk_false_per_frame']:.1f} | {score.clipped_inputs} | {score.adc_clipped} | "
            f"{score.compile_s + score.run_s:.0f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="seeds 0-1 of the presets and seed 0 of the hard cases, no TI")
    parser.add_argument("--targets", "--target", default=",".join(TARGETS))
    parser.add_argument("--case", action="append", default=[],
                        help="hard case(s) to run, comma-separated (repeatable): "
                             f"{', '.join(HARD_CASES)}; skips the preset and capture rows")
    parser.add_argument("--seeds", default=None,
                        help="measured seeds of the hard cases, e.g. 0,1,2 (default 0-2)")
    parser.add_argument("--motifs", default="", help="node=motif,... for every chain")
    parser.add_argument("--json", default=None, help="write the hard cases' totals here")
    parser.add_argument("--out", default=None,
                        help="markdown file (default docs/chip_accuracy.md without --case)")
    parser.add_argument("--list", action="store_true", help="list the hard cases and exit")
    parser.add_argument("--presets-only", action="store_true",
                        help="only the preset scenes and captures (no hard cases)")
    parser.add_argument("--auto", action="store_true",
                        help="preset scenes and hard cases: the measured compile "
                             "(radarsnn.compile_graph's defaults: the accuracy contract on "
                             "the held-back calibration "
                             "seed 102, motifs chosen by it; docs/accuracy.md)")
    args = parser.parse_args(argv)
    if args.list:
        for name, case in HARD_CASES.items():
            print(f"{name:18} {SCENE_CASES[case.scene].sensor:8} {case.summary}; "
                  f"{SCENE_CASES[case.scene].summary}")
        return 0
    motifs = _motifs(args.motifs)
    chosen = [c for item in args.case for c in item.split(",") if c]
    unknown = [c for c in chosen if c not in HARD_CASES]
    if unknown:
        parser.error(f"unknown case(s) {unknown}; cases: {', '.join(HARD_CASES)}")
    hard_seeds = ([int(x) for x in args.seeds.split(",")] if args.seeds else
                  [0] if args.quick else [0, 1, 2])
    out_path = args.out if args.out is not None else (None if chosen else
                                                      "docs/chip_accuracy.md")
    seeds = range(2) if args.quick else range(5)
    lines = ["| target | case | cell sensitivity | cell precision | truth found "
             "(conv / spiking) | false objects (conv / spiking) | clipped inputs |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    hard_lines, scores = list(HARD_HEADER), []
    start = time.perf_counter()
    for target in args.targets.split(","):
        if not chosen:
            lines += preset_rows(target, seeds, args.quick, motifs, args.auto)
        for name in chosen or ([] if args.presets_only else list(HARD_CASES)):
            try:
                score = measure_case(name, target, seeds=hard_seeds, motifs=motifs,
                                     calibration_seeds=(*CALIBRATION_SEEDS, HELD_BACK_SEED)
                                     if args.auto else CALIBRATION_SEEDS, measured=args.auto)
            except CompileError as err:  # the target refuses a motif: say so, do not stop
                given = ", ".join(f"{k}={v}" for k, v in motifs.items()) or "defaults"
                hard_lines.append(f"| {target} | {name} | {given} | {_refused(err)} "
                                  "| | | | | | | |")
                print(hard_lines[-1], flush=True)
                continue
            scores.append(score)
            hard_lines.append(hard_row(score))
            print(hard_lines[-1], flush=True)
    seconds = time.perf_counter() - start
    print("\n" + "\n".join(hard_lines))
    print("targets found: ground truth within ± 1 bin; chirp_sequence_1d counts (target, chirp) "
          "pairs")
    if args.json:
        Path(args.json).write_text(json.dumps([s.as_dict() for s in scores], indent=1),
                                   encoding="utf-8")
    if out_path:
        _write_markdown(Path(out_path), argv, seconds, lines if not chosen else [],
                        hard_lines, hard_seeds)
    print(f"\n{seconds:.0f} s" + (f"; written to {out_path}" if out_path else ""))
    return 0


def _write_markdown(out: Path, argv, seconds: float, lines: list[str], hard_lines: list[str],
                    hard_seeds: list[int]) -> None:
    command = "python benchmarks/chip_accuracy.py " + " ".join(argv or sys.argv[1:])
    machine = (f"{platform.machine()}, {os.cpu_count()} cores, Python "
               f"{platform.python_version()}, numpy {np.__version__}")
    text = "\n".join([
        "# Chip accuracy: spiking vs conventional chain per hardware profile", "",
        f"Produced by `{command.strip()}` in {seconds:.0f} s on {machine}.",
        "Calibration: frames of seeds 100 and 101 (never measured); measured seeds as listed;",
        *(["Compiled as `radarsnn.compile_graph` does by default (`--auto`): seed 102 is also",
           "calibration, held back for the accuracy contract that chooses the motifs",
           "(docs/accuracy.md);"] if "--auto" in command else []),
        "the dynamic-range scenes use seeds 0-1. Sensitivity and precision are cell-level",
        "against the conventional chain's detections; targets and false objects are",
        "detection peaks (± 1 bin) against the ground truth (`radarsnn.demo.matching`).", "",
        *(lines + [""] if lines else []),
        "## Hard cases", "",
        f"Scenes of `radar.scene_cases` drawn per seed; calibrated on seeds 100-101, measured on "
        f"seeds {', '.join(map(str, hard_seeds))} (`radarsnn.demo.hard_cases`). Targets found "
        "by each chain on its own; for `chirp_sequence_1d` (target, chirp) pairs.", "",
        *hard_lines, "",
        *(["Placement: " + "; ".join(sorted(BOARDS.values())) + " — a board profile of "
            "that many chips (`chips` raised; accuracy does not depend on placement).", ""]
          if BOARDS else [])])
    old = out.read_text(encoding="utf-8") if out.is_file() else ""
    notes = old[old.index("## Notes"):] if "## Notes" in old else ""  # hand-written
    out.write_text(text + ("\n" + notes if notes else ""), encoding="utf-8")


if __name__ == "__main__":
    raise SystemExit(main())
