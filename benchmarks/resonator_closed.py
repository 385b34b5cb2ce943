"""The resonators' closed form against the per-step one it replaced, and its floor, in one run.

``python benchmarks/resonator_closed.py [--repeats 5] [--frames 8]`` compiles the carrada
range-Doppler chain with ``resonator`` DFTs for ``loihi2`` (12-bit fixed-point rotations, as
``radarsnn bench --motif resonator``), then times, each call in turn with the others (one BLAS
thread, medians): ``run_program`` on one frame as a user calls it, the same with the plans built
once, the same with the previous resonator solver
(:func:`backends.reference.resonator.solve_resonator`, the step arithmetic over the full drive
histogram) patched in, and the floor (:func:`backends.reference.floor.rotation_floors`).  A
frames axis of ``--frames`` frames is timed once per engine.  The outputs of the two solvers are
checked equal.
"""

from __future__ import annotations

import argparse
import os
import time
from unittest import mock

import numpy as np
from threadpoolctl import threadpool_limits

import backends.reference.closed as closed
from backends.reference import program_plans, run_program
from backends.reference.floor import floor_calls, rotation_floors
from backends.reference.resonator import solve_resonator
from backends.reference.spans import charge, drive
from compiler.chains import range_doppler_chain
from compiler.compile import compile_graph
from radar.config import preset
from radar.scene import SCENE_PRESETS, simulate_frames
from radarsnn.bench import interleaved_medians


def _previous(plan, pid, arrivals, n_frames, first):
    """The closed form before: the step arithmetic over the full drive histogram."""
    pop = plan.populations[pid]
    dtype = np.int64 if plan.integer else np.float64
    return solve_resonator(plan.neurons[pid],
                           lambda s0, s1: drive(arrivals, s0, s1, n_frames, pop.dims, dtype),
                           n_frames * pop.size, first, charge)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--frames", type=int, default=8)
    args = ap.parse_args(argv)
    config, scene = preset("carrada"), SCENE_PRESETS["carrada"]()
    program = compile_graph(range_doppler_chain(config), "loihi2", motifs={"dft": "resonator"},
                            calibration_inputs={"adc": simulate_frames(config, scene, (1, 2, 3))},
                            accuracy="off")
    frames = simulate_frames(config, scene, tuple(range(10, 10 + args.frames)))
    one, many = {"adc": frames[0]}, {"adc": frames}
    kw = {"out_of_range": "clip", "max_time_s": None}
    plans = program_plans(program)
    patch = mock.patch.object(closed, "solve_resonators", _previous)
    load = os.getloadavg()
    with threadpool_limits(limits=1):
        def before():
            with patch:
                return run_program(program, one, plans=plans, **kw)

        fns = {"after": lambda: run_program(program, one, **kw),
               "after_plans": lambda: run_program(program, one, plans=plans, **kw),
               "before_plans": before,
               **{k: v for k, v in floor_calls([], rotations=rotation_floors(plans)).items()
                  if k == "floor"}}
        s = interleaved_medians(fns, args.repeats)
        t0 = time.perf_counter()
        new = run_program(program, many, plans=plans, **kw)
        s["after_frames"] = time.perf_counter() - t0
        with patch:
            t0 = time.perf_counter()
            old = run_program(program, many, plans=plans, **kw)
            s["before_frames"] = time.perf_counter() - t0
    same = all(np.array_equal(new.values[k], old.values[k]) for k in new.values)
    n = args.frames
    print(f"carrada range-Doppler chain, resonator DFTs for loihi2 (12-bit), one BLAS thread, "
          f"median of {args.repeats}, load average {load[0]:.2f} before, "
          f"{os.getloadavg()[0]:.2f} after ({os.cpu_count()} cores)")
    print(f"run_program, one frame:          {s['after']:.3f} s ({1 / s['after']:.2f} frames/s)")
    print(f"  plans built once:              {s['after_plans']:.3f} s, previous resonator "
          f"solver {s['before_plans']:.3f} s ({s['before_plans'] / s['after_plans']:.1f}x)")
    print(f"run_program, {n} frames axis:     {s['after_frames']:.2f} s "
          f"({n / s['after_frames']:.2f} frames/s), previous {s['before_frames']:.2f} s "
          f"({n / s['before_frames']:.2f} frames/s)")
    print(f"floor (the rotations):           {s['floor']:.3f} s; closed/floor "
          f"{s['after_plans'] / s['floor']:.2f} (previous {s['before_plans'] / s['floor']:.2f})")
    print(f"outputs of the two solvers equal: {same}")


if __name__ == "__main__":
    main()
