r"""Benchmark: the reference simulator (step and closed form) against Brian2 and numpy's FFT.

The network is the time-coded S-FT (range DFT) of ``N = 256`` real samples,
replicated over ``C`` chirps with one shared weight matrix:

* source population ``adc = {chirp: C, sample: N}``, linear :class:`LatencyCode`
  on ``[-1, 1]`` over the window ``T = 256`` steps (``t_j = rint((1 - x_j)/2 · T)``;
  ``x = -1`` gives ``t = T``, no spike);
* neuron population ``sft = {chirp: C, bin: N/2, part: 2}``: Re and Im of the
  bins ``0 … N/2-1``, ramp neurons (``du = dv = 0``, ``fire_once``), phases
  silent ``[0, T)`` (spiking off, bias 0) and charging ``[T, 2T)`` (input off,
  bias ``b = 2 v_th / T``); ``n_steps = 2T = 512``;
* one :class:`MatrixProjection` ``contract=("sample",)``, ``produce=("bin", "part")``
  with ``W[j, 2k] = cos(2πkj/N)``, ``W[j, 2k+1] = -sin(2πkj/N)``, rounded to
  multiples of ``2^-10`` so that every membrane sum is exact in float64 and
  Brian2's summation order cannot change a spike step: 65 536 synapses stored
  once, 65 536 · C instances;
* a ``spike_time`` decoder: the membrane after the silent stage is
  ``V_k = Σ_j W_kj (T - t_j)`` and the neuron fires at
  ``t_s = T - 1 + ceil((v_th - V_k)/b)``, so ``V_k ≈ b (1.5T - 0.5 - t_s)`` and
  the DFT estimate is ``V_k · Δx / T`` (``Δx = 2``).  ``v_th`` is the power of
  two just above the largest ``|V_k|`` over bins ``k ≥ 1`` (bin 0 carries the
  latency offset ``-x_min`` and saturates, as in the paper), which makes ``b``
  dyadic.

Printed, all from one run and each figure the median of ``--repeats`` (≥ 5) runs:
``simulate(mode="step")`` and ``mode="closed"`` with the plan built in each call and with a
plan built once and reused (``plan=``; Brian2's "build" is its code generation and network
construction); Brian2 (numpy target, and cython where a C compiler works) building and
running the same network through :mod:`backends.brian2` with ``dt = 1`` step: build, run,
build + run, and the time inside its code objects; agreement of every neuron's spike step;
the ratio Brian2 / ours for every pair of readings against the goals (closed form ≥ 100×,
step ≥ 10× Brian2's run); weight storage; the numpy FFT's time and the S-FT's accuracy
against it (the paper's RMSE protocol); the machine's load average before and after.
Our side runs with one BLAS thread (threadpoolctl), like Brian2's targets.

Run ``python benchmarks/simulator.py [--chirps 64] [--repeats 7] [--quick]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    SpikingNetwork,
)

N_SAMPLES = 256
WINDOW_STEPS = 256
WEIGHT_LSB = 2.0**-10
X_MIN, X_MAX = -1.0, 1.0


def chirp_matrix(n_chirps: int, n_samples: int = N_SAMPLES, seed: int = 0) -> np.ndarray:
    """Seeded beat signals in ``[-1, 1]``: three tones (moving slightly per chirp) plus noise."""
    rng = np.random.default_rng(seed)
    n = np.arange(n_samples)
    c = np.arange(n_chirps)[:, None]
    x = np.zeros((n_chirps, n_samples))
    for amp, f_bin, doppler in ((0.45, 20.3, 0.11), (0.25, 57.8, -0.07), (0.12, 101.1, 0.23)):
        x += amp * np.cos(2 * np.pi * (f_bin * n / n_samples + doppler * c) + rng.uniform(0, 6.3))
    x += rng.normal(scale=0.02, size=x.shape)
    return np.clip(x, X_MIN, X_MAX)


def dft_weights(n_samples: int = N_SAMPLES) -> np.ndarray:
    """``(N, N)`` real DFT weights, columns ``(bin, part)``, rounded to ``WEIGHT_LSB``."""
    j = np.arange(n_samples)[:, None]
    k = np.arange(n_samples // 2)[None, :]
    phase = 2 * np.pi * j * k / n_samples
    w = np.stack([np.cos(phase), -np.sin(phase)], axis=-1).reshape(n_samples, n_samples)
    return np.round(w / WEIGHT_LSB) * WEIGHT_LSB


def sft_network(x: np.ndarray, window_steps: int = WINDOW_STEPS) -> SpikingNetwork:
    """The S-FT network for the chirp matrix ``x`` (``v_th`` fitted to ``x``, see module doc)."""
    n_chirps, n_samples = x.shape
    code = LatencyCode(t_max=window_steps, x_min=X_MIN, x_max=X_MAX)
    w = dft_weights(n_samples)
    steps = code.spike_steps(x)
    drive = np.where(steps < window_steps, window_steps - steps, 0).astype(float)
    v_peak = np.abs(drive @ w)[:, 2:].max()  # bins k >= 1
    v_th = 2.0 ** np.ceil(np.log2(v_peak * 1.001))
    bias = 2 * v_th / window_steps
    params = NeuronParams(du=0.0, dv=0.0, v_th=v_th, reset="fire_once",
                          phases=(Phase(start_step=0, bias=0.0, spiking_on=False),
                                  Phase(start_step=window_steps, bias=bias, input_on=False)))
    scale = bias * (X_MAX - X_MIN) / window_steps
    t_ref = 1.5 * window_steps - 0.5
    return SpikingNetwork(
        name="sft256", n_steps=2 * window_steps,
        populations=[Population(id="adc", shape={"chirp": n_chirps, "sample": n_samples},
                                source=True),
                     Population(id="sft", shape={"chirp": n_chirps, "bin": n_samples // 2,
                                                 "part": 2}, params=params)],
        projections=[MatrixProjection(id="dft", source="adc", target="sft",
                                      contract=("sample",), produce=("bin", "part"), weights=w)],
        encoders=[Encoder(port="x", population="adc", code=code)],
        decoders=[Decoder(port="y", population="sft", kind="spike_time", scale=scale,
                          t_ref=t_ref, missing=scale * (t_ref - 2 * window_steps),
                          combine="re_im")],
        meta={"v_th": v_th, "bias": bias})


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Median wall time of ``repeats`` calls and the last result."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def paper_rmse(estimate: np.ndarray, reference: np.ndarray) -> float:
    """RMSE after cropping bins ``1 … N/2-1`` and min-max normalising Re|Im jointly (each side)."""
    def norm(z: np.ndarray) -> np.ndarray:
        parts = np.concatenate([z.real, z.imag], axis=-1)
        return (parts - parts.min()) / (parts.max() - parts.min())
    return float(np.sqrt(np.mean((norm(estimate[:, 1:]) - norm(reference[:, 1:])) ** 2)))


def brian2_or_none() -> Any:
    from backends.brian2 import import_brian2
    from ir.errors import SimulationError

    try:
        return import_brian2()
    except SimulationError as exc:
        print(f"brian2: not available; skipping the Brian2 part. {exc}")
        return None


def run_brian2(b2: Any, net: SpikingNetwork, x: np.ndarray, target: str) -> dict:
    """Build and run the same network with :mod:`backends.brian2`; spike steps, timings, bytes."""
    from backends.brian2 import build_model
    from backends.reference.encoding import encode_inputs

    b2.prefs.codegen.target = target
    start = time.perf_counter()
    trains, n_frames, _ = encode_inputs(net, {"x": x})
    model = build_model(b2, net, trains, n_frames)
    built = time.perf_counter()
    model.net.run(net.n_steps * b2.ms, profile=True, namespace={})
    done = time.perf_counter()
    loop_s = sum(float(d / b2.second) for _, d in model.net.profiling_info)
    monitor = model.monitors["sft"]
    first = np.full(net.population["sft"].size, -1, np.int64)
    first[np.asarray(monitor.i[:])[::-1]] = np.rint(
        np.asarray(monitor.t[:] / b2.ms)[::-1]).astype(np.int64)
    (syn, _), = model.synapses.values()
    arrays = {}
    for var in syn.variables.values():
        if type(var).__name__ == "DynamicArrayVariable" and var.size == len(syn):
            value = var.get_value()
            arrays[value.__array_interface__["data"][0]] = value.nbytes
    return {"build_s": built - start, "run_s": done - built, "loop_s": loop_s, "first": first,
            "n_synapses": len(syn), "synapse_bytes": sum(arrays.values())}


def c_compiler_works(b2: Any) -> bool:
    """Whether Brian2's cython target can compile here (tries a 1-neuron run)."""
    try:
        b2.prefs.codegen.target = "cython"
        group = b2.NeuronGroup(1, "v : 1")
        group.run_regularly("v = v + 1")
        b2.Network(group).run(2 * b2.defaultclock.dt)
        return True
    except Exception as exc:  # compiler missing or broken: report and go on
        print(f"cython target: not usable ({type(exc).__name__}: {exc})")
        return False


#: Goals of issue 3: Brian2 run time / ours.
GOALS = {"closed": 100.0, "step": 10.0}


def load_average() -> str:
    """The 1/5/15-minute load averages and the core count, as text."""
    try:
        one, five, fifteen = os.getloadavg()
    except OSError:
        return "load average: unavailable"
    return f"load average {one:.2f} / {five:.2f} / {fifteen:.2f} on {os.cpu_count()} cores"


def time_ours(net: SpikingNetwork, x: np.ndarray, repeats: int) -> dict:
    """Median times of ``simulate`` per mode, plan built in each call and reused; results."""
    from threadpoolctl import threadpool_limits

    from backends.reference import build_plan, simulate

    ours = {}
    # one BLAS thread, like Brian2's numpy and cython targets: on 2 cores a multi-threaded
    # OpenBLAS spends ~8 ms waking its threads for each of these small products
    with threadpool_limits(limits=1):
        plan_s, plan = median_time(lambda: build_plan(net), repeats)
        ours["plan"] = plan_s
        for mode in ("step", "closed"):
            simulate(net, {"x": x}, mode=mode, plan=plan)  # warm caches once
            times: dict[str, list[float]] = {"built": [], "reused": []}
            for _ in range(repeats):  # interleaved: both readings see the same machine state
                for key, given in (("built", None), ("reused", plan)):
                    start = time.perf_counter()
                    result = simulate(net, {"x": x}, mode=mode, plan=given)
                    times[key].append(time.perf_counter() - start)
            built, reused = (statistics.median(times[k]) for k in ("built", "reused"))
            ours[mode] = {"built": built, "reused": reused, "result": result}
            print(f"ours {mode:6s}: {built * 1e3:8.2f} ms plan built in the call, "
                  f"{reused * 1e3:8.2f} ms plan reused (medians of {repeats}, interleaved, "
                  "one BLAS thread)")
    print(f"build_plan alone: {plan_s * 1e3:.2f} ms (median of {repeats})")
    return ours


def print_ratios(ours: dict, brian: dict) -> None:
    """Brian2 time / ours for every reading, marking the goals (against Brian2's run)."""
    readings = [(f"{t} {what}", r[key]) for t, r in brian.items()
                for what, key in (("run", "run_s"), ("build+run", "total_s"),
                                  ("code objects", "loop_s"))]
    print("ratio Brian2 / ours (goal: closed >= 100x, step >= 10x Brian2's run):")
    print("  " + " " * 22 + "".join(f"{name:>22s}" for name, _ in readings))
    for mode in ("closed", "step"):
        for plan in ("built", "reused"):
            ratios = [seconds / ours[mode][plan] for _, seconds in readings]
            cells = [f"{r:9.1f}x" + (" (goal met)" if name.endswith(" run") and
                                      r >= GOALS[mode] else
                                      " (goal missed)" if name.endswith(" run") else "")
                     for (name, _), r in zip(readings, ratios, strict=True)]
            print(f"  {mode + ', plan ' + plan:22s}" + "".join(f"{c:>22s}" for c in cells))


def breakdown(net: SpikingNetwork, x: np.ndarray, repeats: int) -> None:
    """Where the time of one ``simulate`` goes: each part timed alone (medians, one thread).

    The step engine's parts are replayed outside the loop on the same data: the
    input currents of every step (:class:`~backends.reference.delivery.TrainCurrents`),
    their in-place additions to ``u``, and the neuron updates of the silent stage
    (``v += u``) and of the charging stage (``v += b``, threshold test) — what
    remains of ``run_step`` is the loop itself (ring buffers, first spikes).
    """
    from threadpoolctl import threadpool_limits

    from backends.reference import build_plan, simulate
    from backends.reference.closed import run_closed
    from backends.reference.decoding import decode_outputs
    from backends.reference.delivery import TrainCurrents
    from backends.reference.encoding import encode_inputs
    from backends.reference.live_neurons import LiveNeurons
    from backends.reference.step import run_step

    plan = build_plan(net)
    trains, n_frames, framed = encode_inputs(net, {"x": x})
    dl, params = plan.deliveries["dft"], plan.neurons["sft"]
    flat, steps = trains["adc"].all_events()
    n, window = net.population["sft"].size * n_frames, net.n_steps // 2

    def currents() -> list:
        ahead = TrainCurrents(dl, 0, 0, flat, steps, n_frames, net.n_steps)
        return [ahead.at(t) for t in range(window)]

    rows = [r for r in currents() if r is not None]
    u = np.zeros(n)

    def add_all() -> None:
        for hit, part in rows:
            dl.add_rows(hit, part, u)

    def stage(start: int, stop: int, v0: np.ndarray, u0: float) -> Callable[[], None]:
        def run() -> None:
            live = LiveNeurons(params, n)
            live.v[:] = v0
            if u0:
                live.u[:], live._u_zero = u0, False
            for t in range(start, stop):
                live.step(t, [], None)
        return run

    closed = run_closed(plan, trains, n_frames)
    parts = {
        "simulate(step), plan reused": lambda: simulate(net, {"x": x}, mode="step", plan=plan),
        "  run_step (the engine alone)": lambda: run_step(plan, trains, n_frames),
        "    input currents, all steps (TrainCurrents)": currents,
        "    u += currents (add_rows), all steps": add_all,
        "    silent stage neuron updates (v += u)": stage(0, window, np.zeros(n), 1.0),
        "    charging stage (v += b, threshold)":  # from the membranes after the silent stage
            stage(window, net.n_steps, closed.membrane["sft"].ravel() - window * net.meta["bias"],
                  0.0),
        "  encode_inputs": lambda: encode_inputs(net, {"x": x}),
        "  decode_outputs": lambda: decode_outputs(net, closed, framed),
        "simulate(closed), plan reused": lambda: simulate(net, {"x": x}, mode="closed",
                                                          plan=plan),
        "  run_closed (the engine alone)": lambda: run_closed(plan, trains, n_frames),
        "build_plan": lambda: build_plan(net),
    }
    print(f"breakdown (medians of {repeats}, one BLAS thread; parts timed alone):")
    with threadpool_limits(limits=1):
        for name, fn in parts.items():
            seconds, _ = median_time(fn, repeats)
            print(f"  {name:48s} {seconds * 1e3:8.2f} ms")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--chirps", type=int, default=64, help="chirps (repetitions), default 64")
    parser.add_argument("--repeats", type=int, default=7,
                        help="timed runs per figure (median), at least 5")
    parser.add_argument("--quick", action="store_true", help="8 chirps, numpy target only")
    parser.add_argument("--breakdown", action="store_true",
                        help="also time the parts of one simulate call")
    args = parser.parse_args(argv)
    chirps = 8 if args.quick else args.chirps
    repeats = max(args.repeats, 5)

    from backends.reference import build_plan

    print(f"before: {load_average()}")
    x = chirp_matrix(chirps)
    net = sft_network(x)
    print(f"network: {chirps} chirps x {N_SAMPLES} samples -> {net.n_neurons} neurons, "
          f"{net.n_synapses} stored synapses ({net.n_synapse_instances()} instances), "
          f"{net.n_steps} steps, v_th={net.meta['v_th']:g}, bias={net.meta['bias']:g}")
    ours = time_ours(net, x, repeats)
    first = ours["step"]["result"].first_spike_steps["sft"].reshape(-1)
    same_modes = np.array_equal(first, ours["closed"]["result"].first_spike_steps["sft"].ravel())
    print(f"step vs closed spike steps identical: {same_modes}")
    fft_s, ref = median_time(lambda: np.fft.rfft(x, axis=-1)[:, :N_SAMPLES // 2], 20 * repeats)
    y = ours["step"]["result"].outputs["y"]
    print(f"numpy rfft: {fft_s * 1e3:.3f} ms; closed / fft = "
          f"{ours['closed']['reused'] / fft_s:.0f}x, step / fft = "
          f"{ours['step']['reused'] / fft_s:.0f}x slower (plans reused); S-FT RMSE vs FFT "
          f"(paper protocol, bins 1..{N_SAMPLES // 2 - 1}) = {paper_rmse(y, ref):.4f}")
    plan_bytes = build_plan(net).weight_nbytes
    print(f"our weight storage (plan): {plan_bytes / 2**20:.2f} MiB")
    if args.breakdown:
        breakdown(net, x, repeats)

    b2 = brian2_or_none()
    if b2 is None:
        print(f"after: {load_average()}")
        return
    b2.BrianLogger.log_level_warn()
    targets = ["numpy"] + ([] if args.quick else ["cython"] if c_compiler_works(b2) else [])
    print(f"brian2 {b2.__version__} with numpy {np.__version__}; targets: {targets}")
    brian = {}
    for target in targets:
        warm = run_brian2(b2, net, x, target)  # cython compiles here; numpy warms caches
        runs = [run_brian2(b2, net, x, target) for _ in range(repeats)]
        brian[target] = {
            "build_s": statistics.median(r["build_s"] for r in runs),
            "run_s": statistics.median(r["run_s"] for r in runs),
            "total_s": statistics.median(r["build_s"] + r["run_s"] for r in runs),
            "loop_s": statistics.median(r["loop_s"] for r in runs)}
        b = brian[target]
        agree = float(np.mean(runs[-1]["first"] == first))
        print(f"brian2 {target}: build {b['build_s']:.3f} s, run {b['run_s']:.3f} s, build+run "
              f"{b['total_s']:.3f} s, code objects {b['loop_s']:.3f} s (medians of {repeats}; "
              f"first run {warm['build_s'] + warm['run_s']:.2f} s); {runs[-1]['n_synapses']} "
              f"synapses (no sharing), {runs[-1]['synapse_bytes'] / 2**20:.1f} MiB synapse "
              f"arrays = {runs[-1]['synapse_bytes'] / plan_bytes:.0f}x our weight storage")
        print(f"  spike-step agreement with ours: {agree:.4%} of {first.size} neurons")
    print_ratios(ours, brian)
    print(f"after: {load_average()}")


if __name__ == "__main__":
    main()
