"""Every motif, compiled small for ``loihi`` and ``loihi2``, in Lava's and NengoLoihi's models.

``python benchmarks/chip_models.py [--models lava,nengo-loihi] [--targets loihi,loihi2,
loihi-programmable] [--out FILE.md]``

For each motif (time-coded S-FT, rate S-DFT, S-FFT, OS-CFAR, CA-CFAR, resonator, graded
read-out, LIF layer) a small network is compiled by the real pipeline, saved, run in each
chip model (the cross-check environment, ``radarsnn crosscheck --build-env``) and in the
reference step engine (int64), and compared spike for spike (first spikes of fire-once
populations).  A row says ``exact``, the mismatches, or why the chip's stock neurons cannot
express the network.  It prints the table and writes it to ``--out``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backends.crosscheck.env import build_env  # noqa: E402
from backends.crosscheck.run import compare, membrane_difference, run_chip_model  # noqa: E402
from compiler.compile import compile_graph  # noqa: E402
from compiler.hardware import load_profile  # noqa: E402
from ir import Graph  # noqa: E402
from ir.errors import RadarSNNError  # noqa: E402


def _dft(n: int) -> Graph:
    return Graph.from_dict({"name": "dft", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": n}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin"},
        {"id": "o", "op": "output", "input": "f"}]})


def _cfar(kind: str) -> Graph:
    extra = {"k": 20} if kind == "os" else {}
    return Graph.from_dict({"name": "cfar", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 32, "doppler": 16}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "x", "kind": kind, "guard": [1, 1],
         "train": [2, 2], "alpha": 3.0, "edge": ["clip", "wrap"], **extra},
        {"id": "o", "op": "output", "input": "det"}]})


def _maps() -> np.ndarray:
    m = np.random.default_rng(3).exponential(1.0, size=(2, 32, 16))
    m[:, 5, 3] = m[:, 20, 11] = 30.0
    return m


SAMPLES = np.random.default_rng(1).normal(size=(2, 16))
#: motif -> (graph, calibration/input, compile options)
CASES = {
    "time-coded S-FT": (_dft(16), {"x": SAMPLES}, {"motifs": {"dft": "time"},
                                                   "options": {"output_spikes": "time"}}),
    "rate S-DFT": (_dft(16), {"x": SAMPLES}, {"motifs": {"dft": "rate"}, "time_steps": 256}),
    "S-FFT (radix 4)": (_dft(16), {"x": SAMPLES}, {"motifs": {"dft": "time-fft"},
                                                   "time_steps": 32}),
    "OS-CFAR": (_cfar("os"), {"x": _maps()}, {}),
    "CA-CFAR": (_cfar("ca"), {"x": _maps()}, {}),
    "resonator": (_dft(16), {"x": SAMPLES}, {"motifs": {"dft": "resonator"}}),
    "graded read-out": (_dft(16), {"x": SAMPLES}, {"motifs": {"dft": "time"},
                                                   "options": {"output_spikes": "graded"}}),
}


#: ``--targets loihi-programmable``: loihi's number formats with neurons that have every
#: feature — what the stock chip does with the motifs the ``loihi`` compile refuses.
PROGRAMMABLE = {"current_decay_offset_lsb": 0, "full_voltage_decay": True,
                "reset": "programmable", "fire_once": "programmable",
                "threshold_schedule": True, "input_gate": True}


def _profile(target: str):
    if target == "loihi-programmable":
        return load_profile("loihi").model_copy(update={**PROGRAMMABLE, "name": target})
    return target


def _row(motif: str, target: str, model: str, python: Path) -> str:
    graph, data, kw = CASES[motif]
    try:
        program = compile_graph(graph, _profile(target), calibration_inputs=data, **kw)
    except RadarSNNError as err:
        text = " ".join(str(err).split())
        why = (text.split(", which the stock neurons")[0] if "stock neurons" in text
               else text[:120])
        return f"| {motif} | {target} | {model} | does not compile: {why} |"
    cells = []
    for net in program.networks:
        inputs = data if set(data) >= {e.port for e in net.encoders} else None
        if inputs is None:
            cells.append(f"{net.name}: fed by a host segment (not run)")
            continue
        try:
            chip, ref = run_chip_model(model, net, inputs, python=python)
        except RadarSNNError as err:
            cells.append(f"worker failed: {' '.join(str(err).split())[-160:]}")
            continue
        if chip.refused:
            cells.append(f"not expressible: {chip.refused}")
            continue
        parts = []
        for m in compare(net, ref, chip):
            verdict = "exact" if m.exact else f"{m.mismatched} of {m.n_spikes_ref} differ"
            parts.append(f"{m.population} ({m.compared}): {verdict}")
        dv = membrane_difference(net, ref, chip)
        parts.append("final v max diff " + ", ".join(f"{k} {v:g}" for k, v in dv.items()))
        cells.append("; ".join(parts))
    return f"| {motif} | {target} | {model} | {' / '.join(cells)} |"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="nengo-loihi,lava")
    ap.add_argument("--targets", default="loihi,loihi2")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    python = build_env()
    lines = ["| motif | target | model | result |", "|---|---|---|---|"]
    start = time.perf_counter()
    for motif in CASES:
        for target in args.targets.split(","):
            for model in args.models.split(","):
                lines.append(_row(motif, target, model, python))
                print(lines[-1], flush=True)
    lines.append(f"\n`python benchmarks/chip_models.py --models {args.models} --targets "
                 f"{args.targets}`, {time.perf_counter() - start:.0f} s")
    if args.out:
        args.out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
