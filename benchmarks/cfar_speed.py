"""Conventional CFAR speed: the fast kernels (radar.cfar_fast) vs the original gathered code.

Times, in one run and on the same 256 x 64 linear-power range-Doppler map of a random
``carrada`` scene (range clipped, Doppler wrapped), each CFAR call the conventional chain
makes (``ir.evaluate`` calls :func:`radar.cfar.cfar`) by the current code and by the
original implementation kept in ``radar.cfar._reference_cfar``, checks that both return
identical arrays (bit for bit) and prints the medians and the ratio old / new.

Cases: the demo chain's OS-CFAR (``compiler.chains.DEFAULT_CFAR``: guard 3/2, train 8/4,
N = 264, k = 198), the study's OS- and CA-CFAR (``benchmarks/cfar.py``: 15 x 15 window,
guard 3, N = 176, k = 132), CA on the same map rounded to integers (summed-area tables),
and the OS threshold (``cfar_threshold``), which still gathers (ratio ~1).  Last, the
whole conventional chain as ``radarsnn bench`` times it (``ir.evaluate`` of
``compiler.chains.range_doppler_chain`` on one carrada frame, one BLAS thread), with
``radar.cfar.cfar`` and with it swapped for the original implementation.

Usage::

    python benchmarks/cfar_speed.py               # 15 repeats per figure
    python benchmarks/cfar_speed.py --repeats 31
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

import numpy as np

__all__ = ["power_map", "median_s", "main"]


def power_map(seed: int = 0) -> np.ndarray:
    """One linear-power ``(256, 64)`` range-Doppler map of a random carrada scene."""
    from radar.config import preset
    from radar.scene import simulate_frame
    from radar.spectra import range_doppler_map
    from radarsnn.sweep.frames import random_scene

    cfg, rng = preset("carrada"), np.random.default_rng(seed)
    frame = simulate_frame(cfg, random_scene(rng), seed=int(rng.integers(2**31)))
    return range_doppler_map(frame.adc, magnitude="square", keep="all")


def median_s(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``repeats`` calls of ``fn`` (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _cases(x: np.ndarray) -> list[tuple[str, str, np.ndarray, dict]]:
    from radar.cfar_theory import ca_alpha, os_alpha
    from radar.cfar_window import n_training

    edge = ["clip", "wrap"]
    demo = {"guard": [3, 2], "train": [8, 4], "edge": edge}
    study = {"guard": [3, 3], "train": [4, 4], "edge": edge}
    n_demo, n_study = n_training([3, 2], [8, 4]), n_training([3, 3], [4, 4])
    os_demo = demo | {"kind": "os", "k": 198, "alpha": float(os_alpha(1e-6, n_demo, 198))}
    os_study = study | {"kind": "os", "k": 132, "alpha": float(os_alpha(1e-6, n_study, 132))}
    ca_study = study | {"kind": "ca", "alpha": float(ca_alpha(1e-6, n_study))}
    return [
        ("OS demo chain  (N=264, k=198)", "cfar", x, os_demo),
        ("OS study       (N=176, k=132)", "cfar", x, os_study),
        ("CA study       (N=176)", "cfar", x, ca_study),
        ("CA integer map (N=176, SAT)", "cfar", np.rint(x / np.median(x)), ca_study),
        ("OS threshold   (N=264, gather)", "threshold", x, os_demo),
    ]


def main(argv: list[str] | None = None) -> None:
    """Print old / new medians per case and the ratio; fail if any result differs."""
    from radar.cfar import _reference_cfar, _reference_noise_estimate, cfar, cfar_threshold

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=15, help="timed calls per figure")
    parser.add_argument("--seed", type=int, default=0, help="scene seed")
    args = parser.parse_args(argv)
    x = power_map(args.seed)
    print(f"map {x.shape}, {args.repeats} repeats, load average {os.getloadavg()[0]:.2f}")
    print(f"{'case':32s} {'old ms':>8s} {'new ms':>8s} {'old/new':>8s}  identical")
    for name, what, arr, params in _cases(x):
        if what == "cfar":
            new = lambda a=arr, p=params: cfar(a, **p)  # noqa: E731
            old = lambda a=arr, p=params: _reference_cfar(a, **p)  # noqa: E731
        else:
            new = lambda a=arr, p=params: cfar_threshold(a, **p)  # noqa: E731
            rest = {key: v for key, v in params.items() if key != "alpha"}
            old = lambda a=arr, p=rest, s=params["alpha"]: s * _reference_noise_estimate(a, **p)  # noqa: E731
        same = np.asarray(new()).tobytes() == np.asarray(old()).tobytes()
        t_old, t_new = median_s(old, args.repeats), median_s(new, args.repeats)
        print(f"{name:32s} {t_old * 1e3:8.2f} {t_new * 1e3:8.2f} {t_old / t_new:7.1f}x  {same}")
        if not same:
            raise SystemExit(f"{name}: the fast path differs from the original implementation")
    _chain(args.repeats)
    print(f"load average after {os.getloadavg()[0]:.2f}")


def _chain(repeats: int) -> None:
    """The conventional carrada chain (``ir.evaluate``) with the new and the original CFAR."""
    from threadpoolctl import threadpool_limits

    import radar.cfar as cfar_module
    from compiler.chains import range_doppler_chain
    from ir import evaluate
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame

    config = preset("carrada")
    frame = simulate_frame(config, SCENE_PRESETS["carrada"](), seed=0).adc
    graph = range_doppler_chain(config)
    run = lambda: evaluate(graph, {"adc": frame})  # noqa: E731
    import ir.ops.compare as golden  # the interpreter's CFAR (CFAR.evaluate) is radar.cfar.cfar

    fast = golden.cfar
    with threadpool_limits(limits=1):
        new_out, t_new = run(), median_s(run, repeats)
        golden.cfar = cfar_module._reference_cfar
        try:
            old_out, t_old = run(), median_s(run, repeats)
        finally:
            golden.cfar = fast
    same = all(np.asarray(new_out[key]).tobytes() == np.asarray(old_out[key]).tobytes()
               for key in new_out)  # fmt: skip
    name = "conventional chain (ir.evaluate)"
    print(f"{name:32s} {t_old * 1e3:8.2f} {t_new * 1e3:8.2f} {t_old / t_new:7.1f}x  {same}")
    if not same:
        raise SystemExit(f"{name}: outputs differ from the original implementation")


if __name__ == "__main__":
    main()
