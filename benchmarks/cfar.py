"""Spiking OS-/CA-CFAR vs the conventional CFAR on simulated CARRADA-like range-Doppler maps.

Protocol (Vogginger et al. 2022, section 4.1, Eq. 13-14): ``radar.scene`` frames of the
``carrada`` preset with random scenes of 1-3 targets (pedestrians, cyclists, cars), Tx->Rx
leakage, static clutter and receiver noise; the map is the rx-summed power ``|X|^2``
(256 range x 64 Doppler, Hann range window) in dB (``10 log10``, the form CARRADA ships) or
linear.  The CFAR: 15 x 15 window, guard 3 and train 4 per side (N = 176), range clipped,
Doppler wrapped; OS with the k = 132nd largest (~3N/4).  The spiking networks are compiled
with ``verify -> calibrate -> lower`` (calibration on separate maps) and simulated on the
step grid (``mode="step"``, faster here than the closed form); sensitivity ``TP/(TP+FN)``
and precision ``TP/(TP+FP)`` are pooled over all maps against the conventional decisions on
the same map.

Usage::

    python benchmarks/cfar.py                 # 1 000 maps (about an hour on 2 cores)
    python benchmarks/cfar.py --maps 100 --steps 10 50 100 500
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from compiler.compile import lower_pass
from ir import Graph
from radarsnn.sweep.frames import random_scene  # the sweep's scene model, shared

__all__ = ["ALPHA", "K_OS", "rd_maps", "random_scene", "study_graph", "score", "main"]

#: Threshold factor per CFAR kind and map domain (the detection load is printed).
ALPHA = {"os": {"db": 1.2, "power": 10.0}, "ca": {"db": 1.2, "power": 20.0}}
#: OS rank: the 132nd largest of 176 training cells.
K_OS = 132
SHAPE = {"range": 256, "doppler": 64}


def rd_maps(n: int, *, seed: int) -> np.ndarray:
    """``n`` linear-power range-Doppler maps ``(n, 256, 64)`` of random carrada scenes."""
    from radar.config import preset
    from radar.scene import simulate_frame
    from radar.spectra import range_doppler_map

    cfg, rng = preset("carrada"), np.random.default_rng(seed)
    out = np.empty((n, 256, 64))
    for i in range(n):
        frame = simulate_frame(cfg, random_scene(rng), seed=int(rng.integers(2**31)))
        out[i] = range_doppler_map(frame.adc, magnitude="square", keep="all")
    return out


def study_graph(kind: str, domain: str) -> Graph:
    """The studied chain: a stored 256 x 64 map ``rd`` -> ``cfar`` ``det`` -> output."""
    params = {"kind": kind, "axes": ["range", "doppler"], "guard": [3, 3], "train": [4, 4],
              "alpha": ALPHA[kind][domain], "edge": ["clip", "wrap"]}
    if kind == "os":
        params["k"] = K_OS
    return Graph.from_dict({"name": f"{kind}-cfar-{domain}", "nodes": [
        {"id": "rd", "op": "input", "shape": SHAPE, "domain": domain},
        {"id": "det", "op": "cfar", "input": "rd", **params},
        {"id": "out", "op": "output", "input": "det"}]})


def score(reference: np.ndarray, spiking: np.ndarray) -> tuple[float, float]:
    """Pooled (sensitivity, precision) of spiking detections against the reference."""
    tp = int(np.sum(reference & spiking))
    fn = int(np.sum(reference & ~spiking))
    fp = int(np.sum(~reference & spiking))
    return tp / max(tp + fn, 1), tp / max(tp + fp, 1)


def _networks(kind, domain, cal, steps):
    from compiler.passes import Verify
    from compiler.passes.base import CompileContext, run_pipeline
    from compiler.passes.calibrate import Calibrate
    from compiler.program import CompiledProgram

    g = study_graph(kind, domain)
    for n in steps:
        ctx = CompileContext(calibration_inputs={"rd": cal})
        yield n, run_pipeline([Verify(), Calibrate(), lower_pass({"time_steps": n})], ctx,
                              CompiledProgram(graph=g)).networks[0]


def main(argv: list[str] | None = None) -> None:
    """Print the sensitivity/precision-vs-steps table per variant and domain."""
    from backends.reference import simulate
    from radar.cfar import cfar

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", type=int, default=1000)
    ap.add_argument("--calibration-maps", type=int, default=20)
    ap.add_argument("--steps", type=int, nargs="+", default=[10, 20, 50, 100, 200, 500, 1000])
    ap.add_argument("--batch", type=int, default=25)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    test, cal = rd_maps(args.maps, seed=1), rd_maps(args.calibration_maps, seed=1000)
    print(f"{args.maps} maps + {args.calibration_maps} calibration maps in "
          f"{time.perf_counter() - t0:.0f} s")
    for domain in ("db", "power"):
        to = (lambda p: 10 * np.log10(p)) if domain == "db" else (lambda p: p)
        x, xc = to(test), to(cal)
        for kind in ("os", "ca"):
            a = ALPHA[kind][domain]
            ref = np.array([cfar(m, kind=kind, guard=[3, 3], train=[4, 4], alpha=a,
                                 k=K_OS if kind == "os" else None, edge=["clip", "wrap"])
                            for m in x])
            print(f"\n{kind.upper()}-CFAR on {domain} maps, alpha={a}: "
                  f"{ref.sum() / len(x):.1f} detections per map (conventional)")
            print(f"{'steps':>6} {'sensitivity':>12} {'precision':>10}  code")
            for n, net in _networks(kind, domain, xc, args.steps):
                spk = np.concatenate([  # calibrated on other maps: clip what is above
                    simulate(net, {"rd": x[i:i + args.batch]}, mode="step",
                             out_of_range="clip").outputs["det"] > 0
                    for i in range(0, len(x), args.batch)])
                sens, prec = score(ref, spk)
                info = net.meta["cfar"]["det"]
                code = info["code"]
                print(f"{n:>6} {100 * sens:>11.2f}% {100 * prec:>9.2f}%  {code['kind']} "
                      f"[{code['x_min']:.4g}, {code['x_max']:.4g}] T={code['t_max']} "
                      f"cut delay {info['cut_delay']}", flush=True)
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
