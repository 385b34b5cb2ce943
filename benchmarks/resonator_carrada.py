"""The carrada chain with ``resonator`` range and Doppler stages beside the S-FT (issue 22).

``python benchmarks/resonator_carrada.py [--seeds 0 1 2]`` compiles
``examples/chains/carrada_rd_oscfar.yaml`` for ``loihi2`` three times — the default S-FT
motifs and ``{rng: resonator, dop: resonator}`` (renormalised, the default, and with
``resonator_renorm: off``) — calibrated on one simulated CARRADA frame (seed 1000, the first
4 virtual channels, as the chain's ``rx: 4``), runs each on the scene frames of the
given seeds and prints the cell sensitivity and precision of their detections against the
conventional chain (numpy), the synapses (total and of the two DFT stages) and the latency per
frame from the resource report.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.report import build_report
from ir import Graph, evaluate
from radar.config import preset
from radar.scene import SCENE_PRESETS, simulate_frame

CHAIN = Path(__file__).resolve().parents[1] / "examples" / "chains" / "carrada_rd_oscfar.yaml"
#: Row name -> (motifs, options): the S-FT, the resonator (renormalised: the default) and the
#: resonator with renormalisation off.
MOTIFS = {"S-FT (default)": ({}, None),
          "resonator (12-bit, renormalised: default)": ({"dft": "resonator"}, None),
          "resonator (12-bit, renorm off)": ({"dft": "resonator"}, {"resonator_renorm": "off"})}


def _frame(seed: int) -> np.ndarray:
    return simulate_frame(preset("carrada"), SCENE_PRESETS["carrada"](), seed=seed).adc[:4]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    args = ap.parse_args(argv)
    graph = Graph.from_yaml(CHAIN)
    calibration = _frame(1000)
    frames = {s: _frame(s) for s in args.seeds}
    conv = {s: np.asarray(evaluate(graph, {"adc": x})["out"], bool) for s, x in frames.items()}
    print(f"carrada chain on loihi2, scenes seeds {args.seeds}, calibrated on seed 1000")
    print("| motif | sensitivity | precision | cells (conv / spiking) | synapses | "
          "DFT synapses | latency steps/frame | latency s/frame | cores | compile+run s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, (motifs, options) in MOTIFS.items():
        t0 = time.perf_counter()
        p = compile_graph(graph, "loihi2", motifs=motifs, calibration_inputs={"adc": calibration},
                          options=options)
        hits = n_conv = n_spk = 0
        for s, x in frames.items():
            out = run_program(p, {"adc": x}, mode="auto", out_of_range="clip").values["out"]
            mask = np.asarray(out, bool)
            hits += int((mask & conv[s]).sum())
            n_conv += int(conv[s].sum())
            n_spk += int(mask.sum())
        rep = build_report(p).data
        dft = sum(r["synapses_total"] for r in rep["stages"]
                  if r["node"].split("__")[0] in ("rng", "dop"))
        lat = rep["latency"]
        print(f"| {name} | {hits / max(1, n_conv):.4f} | {hits / max(1, n_spk):.4f} | "
              f"{n_conv} / {n_spk} | {rep['totals']['synapses']:,} | {dft:,} | "
              f"{lat['total_steps']:,} | {lat['total_s']:.4g} | {rep['totals']['cores']} | "
              f"{time.perf_counter() - t0:.0f} |")


if __name__ == "__main__":
    main()
