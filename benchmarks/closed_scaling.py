"""Closed-form time against the number of frames, next to the simulation guard's estimate.

The network is a compiled OS-CFAR (``--kind os``, default) or CA-CFAR on a
``range x doppler`` power map (default 16 x 8; guard 1 and train 1 cells per side, range
clipped, Doppler wrapped), calibrated on 64 exponential maps and fed with fresh ones
(clipped where they exceed the calibration).  For each frame count the script prints the
median wall time of ``--repeats`` calls of ``simulate(net, x, mode="closed")``, the
guard's estimate (``estimate_simulation(net, n, mode="closed").time_s``), their ratio,
and the time per frame relative to the first frame count (1.0 for an exactly linear
engine).  The machine's load average is printed before and after.

Usage::

    python benchmarks/closed_scaling.py                       # 1 k ... 100 k frames, 3 repeats
    python benchmarks/closed_scaling.py --frames 1000 10000 --repeats 5 --kind ca
    python benchmarks/closed_scaling.py --shape 64 32 --frames 100 1000 5000
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from backends.reference import simulate
from backends.reference.guards import estimate_simulation
from compiler.compile import compile_graph
from compiler.snn import SpikingNetwork
from ir import Graph

FRAMES = (1_000, 2_000, 5_000, 10_000, 20_000, 50_000, 100_000)


def cfar_network(kind: str, shape: tuple[int, int], seed: int = 0) -> SpikingNetwork:
    """The compiled CFAR network of a ``shape`` range x doppler power map."""
    params = {"kind": kind, "axes": ["range", "doppler"], "guard": [1, 1], "train": [1, 1],
              "alpha": 3.0, "edge": ["clip", "wrap"]}
    if kind == "os":
        params["k"] = 6
    graph = Graph.from_dict({"name": f"{kind}-cfar", "nodes": [
        {"id": "rd", "op": "input", "shape": {"range": shape[0], "doppler": shape[1]},
         "domain": "power"},
        {"id": "det", "op": "cfar", "input": "rd", **params},
        {"id": "out", "op": "output", "input": "det"}]})
    calibration = np.random.default_rng(seed).exponential(size=(64, *shape))
    program = compile_graph(graph, target=None, calibration_inputs={"rd": calibration})
    return next(s.network for s in program.segments if s.kind == "spiking")


def median_closed_s(net: SpikingNetwork, x: np.ndarray, repeats: int) -> float:
    """Median wall time of ``simulate(mode="closed")`` on ``x`` (plan built in each call)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        simulate(net, {"rd": x}, mode="closed", out_of_range="clip", max_time_s=None,
                 max_memory_bytes=None)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def load_average() -> str:
    """``os.getloadavg()`` as text (``n/a`` where the platform has none)."""
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "n/a"


def main(argv: list[str] | None = None) -> None:
    """Print one row per frame count: measured, estimated, ratio, per-frame growth."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, nargs="+", default=list(FRAMES))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--kind", choices=["os", "ca"], default="os")
    parser.add_argument("--shape", type=int, nargs=2, default=[16, 8], metavar=("RANGE", "DOPPLER"))
    args = parser.parse_args(argv)
    net = cfar_network(args.kind, tuple(args.shape))
    rng = np.random.default_rng(1)
    x = rng.exponential(size=(max(args.frames), *args.shape))
    print(f"{args.kind}-CFAR {args.shape[0]}x{args.shape[1]}, {net.n_steps} steps, "
          f"{sum(p.size for p in net.populations)} neurons; medians of {args.repeats}; "
          f"load {load_average()}")
    print(f"{'frames':>8} {'measured s':>11} {'estimate s':>11} {'ratio':>6} {'per frame':>10}")
    first = None
    for n in args.frames:
        measured = median_closed_s(net, x[:n], args.repeats)
        estimate = estimate_simulation(net, n, mode="closed").time_s
        first = first or measured / n
        print(f"{n:>8} {measured:>11.3f} {estimate:>11.3f} {measured / estimate:>6.2f} "
              f"{measured / n / first:>10.2f}", flush=True)
    print(f"load {load_average()}")


if __name__ == "__main__":
    main()
