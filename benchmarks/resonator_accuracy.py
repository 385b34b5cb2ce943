"""Accuracy of the ``resonator`` DFT motif against the time-coded S-FT; prints tables.

``python benchmarks/resonator_accuracy.py`` runs:

* ``ti_table()`` — the real TI chirps (first 4, N = 1024 samples, positive bins): the
  magnitude-spectrum error against ``np.fft`` (RMSE of ``|X|`` over bins 1 … N/2−1, each
  spectrum min–max normalised) and the S-FT accuracy protocol's Re/Im RMSE, for the
  resonator (read-out ``time`` with T steps, and ``graded`` on loihi2 / ``log`` on unbounded,
  which has no graded spikes) and the time-coded S-FT
  compiled to the same number of steps per frame, on ``unbounded`` and ``loihi2``;
* ``drift_table()`` — the fixed-point drift bound and the measured error of the loihi2
  resonator for 8 … 18 coefficient fraction bits (8 = the weight format, 12 = the chip's
  format), with periodic renormalisation off and on (``resonator_renorm``; on by default).

Everything runs the closed-form engine (equal to the step engine, tests/test_resonator_*.py).
"""

from __future__ import annotations

import numpy as np

from backends.reference import run_program
from compiler.compile import compile_graph
from compiler.lowering.dft_common import sft_rmse
from ir import Graph
from radar.loaders import load_ti_chirps

N = 1024


def _graph(n: int) -> Graph:
    return Graph.from_dict({"name": f"ti-{n}", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 4, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})


def magnitude_rmse(y: np.ndarray, ref: np.ndarray) -> float:
    """RMSE of the min–max normalised moduli over bins 1 … N/2−1 (mean over chirps)."""
    def norm(a):
        m = np.abs(a[:, 1:])
        lo, hi = m.min(axis=1, keepdims=True), m.max(axis=1, keepdims=True)
        return (m - lo) / (hi - lo)
    return float(np.sqrt(np.mean((norm(y) - norm(ref)) ** 2)))


def _run(x: np.ndarray, target: str, motif: str, t: int, **options):
    p = compile_graph(_graph(x.shape[1]), target, motifs={"f": motif},
                      calibration_inputs={"x": x}, time_steps=t, options=options or None)
    y = run_program(p, {"x": x}, mode="closed").outputs["o"]
    return y, p


def ti_table(readouts=(64, 128, 256)) -> None:
    """Resonator vs S-FT on the TI chirps at equal steps per frame."""
    chirps, _ = load_ti_chirps()
    x = chirps[:4, :N].astype(np.float64)
    ref = np.fft.fft(x, axis=1)[:, :N // 2]
    print(f"TI chirps, N = {N}, 4 chirps: |X| RMSE (min-max normalised, bins 1..N/2-1) and "
          "Re/Im RMSE (the S-FT protocol)")
    print("| target | motif | read-out | steps | synapses | abs RMSE | Re/Im RMSE |")
    print("|---|---|---|---|---|---|---|")
    for target in ("unbounded", "loihi2"):
        rows = []
        for t in (*readouts, None):
            if t is None:  # the held-state read-out: graded spikes where the target has them
                held = "graded" if target == "loihi2" else "log"
                y, p = _run(x, target, "resonator", 256, resonator_readout=held)
                rows.append(("resonator", held, p, y))
            else:
                y, p = _run(x, target, "resonator", t, resonator_readout="time")
                rows.append(("resonator", f"time T={t}", p, y))
            steps = p.networks[0].n_steps
            # the S-FT at the same steps: 2T (time read-out) or T + 1 (graded, loihi2)
            t_sft = steps // 2 if target == "unbounded" else steps - 1
            y2, p2 = _run(x, target, "time", t_sft)
            rows.append(("time (S-FT)", f"T={t_sft}", p2, y2))
        for motif, how, p, y in rows:
            net = p.networks[0]
            print(f"| {target} | {motif} | {how} | {net.n_steps} | {net.n_synapses} | "
                  f"{magnitude_rmse(y, ref):.5f} | {sft_rmse(y, ref, n_fft=N):.5f} |")


def drift_table(bits=(8, 10, 12, 14, 16, 18)) -> None:
    """Fixed-point drift on loihi2 against the coefficient fraction bits, with and without
    periodic renormalisation (``resonator_renorm``: off, and auto — the default)."""
    chirps, _ = load_ti_chirps()
    x = chirps[:4, :N].astype(np.float64)
    ref = np.fft.fft(x, axis=1)[:, :N // 2]
    print(f"\nloihi2 resonator, N = {N}, read-out T = 256: drift against coefficient bits")
    print("| coef bits | renorm | drift bound | weight error | gain drift max | "
          "phase drift (rad) | abs RMSE | Re/Im RMSE |")
    print("|---|---|---|---|---|---|---|---|")
    auto = _run(x, "loihi2", "resonator", 256)[1].networks[0].meta["resonator"]["f"]["coef_bits"]
    for f in sorted({*bits, auto}):
        for renorm in ("off", "auto"):
            y, p = _run(x, "loihi2", "resonator", 256, resonator_coef_bits=f,
                        resonator_drift_max=1e9, resonator_readout="time",
                        resonator_renorm=renorm)
            d = p.networks[0].meta["resonator"]["f"]
            tag = " (chip format)" if f == auto else ""
            how = f"every {d['renorm_steps']}" if d["renorm_steps"] else "none"
            print(f"| {f}{tag} | {renorm}: {how} | {d['bound']:.4f} | {d['weight_error']:.4f} | "
                  f"{d['gain_drift']:.4f} | {d['phase_drift_rad']:.4f} | "
                  f"{magnitude_rmse(y, ref):.5f} | {sft_rmse(y, ref, n_fft=N):.5f} |")


if __name__ == "__main__":
    ti_table()
    drift_table()
