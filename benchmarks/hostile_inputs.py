"""Time and peak memory of the readers and the sweep planner on small hostile files.

Each case runs in a fresh interpreter under an address-space cap (its size after imports +
``--cap-mib``) and a timeout; the table gives the file's size, the seconds and the peak
memory growth of the call, and how it ended. ``--code DIR`` measures another checkout
(e.g. ``git archive OLD radar compiler ir backends | tar -x -C DIR``) on the same files.

A second table reads the test suite's bomb per reader (``tests/bombs.py``,
``reader_bombs``).  Where a test once bounded a case's time (the tests now check the typed
refusal and the memory cap; wall-clock bounds do not belong in tests) the row gives that
bound and ``ok`` or ``SLOW``: 15 s for the ``.mat`` and ``.npz`` bombs, 10 s for the alias
sweep, 2 s for the 2^33-point grid, 3 s for each reader bomb.

    python benchmarks/hostile_inputs.py [--cap-mib 6144] [--timeout-s 120] [--code DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the bomb builders of the test suite

_CHILD = """
import json, resource, sys, time
import numpy, scipy.io, radar.readers, compiler.compile, radarsnn.cli.arrays
import radarsnn.sweep.run
call = {call!r}
pages = int(open("/proc/self/statm").read().split()[0])
resource.setrlimit(resource.RLIMIT_AS, (pages * resource.getpagesize() + {cap}, -1))
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
try:
    exec(call, {{}})
    end = "read"
except BaseException as err:
    end = f"{{type(err).__name__}}: {{str(err)[:90]}}"
print(json.dumps([time.perf_counter() - start,
                  (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024, end]))
"""


#: Case -> the wall-clock bound a test once asserted on it (seconds).
BOUNDS_S = {".mat 1x1 double, 3.9 GiB data element": 15.0,
            ".npz member declaring 3.9 GiB, port (4,)": 15.0,
            "sweep, 120 000 aliases of 400 KB": 10.0,
            "sweep, 33 axes x 2 values, planned": 2.0}

#: The bound each reader bomb of ``tests/bombs.py`` was once held to (seconds).
READER_BOMB_BOUND_S = 3.0


def cases(tmp: Path) -> dict[str, tuple[Path, str]]:
    """Case -> (its file, the call), the files written into ``tmp``."""
    import numpy as np
    import yaml
    from bombs import mat_bomb, npz_bomb

    gib = 1 << 30
    (tmp / "bomb.mat").write_bytes(mat_bomb(int(3.9 * gib)))
    (tmp / "bomb.npz").write_bytes(npz_bomb((int(3.9 * gib) // 8,)))
    np.zeros(48 << 20, dtype="<i2").tofile(tmp / "capture.bin")  # 96 MiB
    big, refs = "x" * 400_000, ", ".join(["*b"] * 120_000)
    (tmp / "aliases.yaml").write_text(f"name: &b {big}\nchains: {{a: c.yaml}}\n"
                                      f"frames: {{source: scene}}\nmode: [{refs}]\n")
    from compiler.compile import EXTRA_OPTIONS
    from radarsnn.sweep.spec import NAMED_AXES

    axes = sorted(set(EXTRA_OPTIONS) | set(NAMED_AXES) - {"chain"})[:33]
    (tmp / "c.yaml").write_text(yaml.safe_dump({"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 4}},
        {"id": "o", "op": "output", "input": "x"}]}))
    (tmp / "grid.yaml").write_text(yaml.safe_dump({
        "name": "g", "chains": {"a": "c.yaml"}, "grid": {a: [0, 1] for a in axes},
        "frames": {"source": "scene", "n_frames": 1, "frames_per_cell": 1}}))
    lols = ['name: &a ["lol"' + ', "lol"' * 8 + "]"]
    lols += [f"x{h}: &{h} [" + ", ".join([f"*{p}"] * 9) + "]"
             for p, h in zip("abcdefgh", "bcdefghi", strict=True)]
    (tmp / "laughs.yaml").write_text("\n".join(lols) + "\nnodes: []\n")  # 9**9 strings
    (tmp / "deep.yaml").write_text("name: " + "[" * 5000 + "\nnodes: []\n")
    (tmp / "long.yaml").write_text("name: long\nnodes:\n- {id: x, op: input, shape: {range: 4}}\n"
                                   + "".join(f"- {{id: o{k}, op: output, input: x}}\n"
                                             for k in range(27_999)))
    chain = "from ir import Graph; Graph.from_yaml(open({p!r}).read())"
    load = ("from radarsnn.cli.arrays import load_arrays; import inspect; load_arrays([{p!r}], "
            "['x'], 'c', **({{'shapes': {{'x': {port}}}}} if 'shapes' in "
            "inspect.signature(load_arrays).parameters else {{}}))")
    return {
        "chain, billion laughs (9^9 strings) as name": (tmp / "laughs.yaml", chain.format(
            p=str(tmp / "laughs.yaml"))),
        "chain, 5 000 nested [ as name": (tmp / "deep.yaml", chain.format(
            p=str(tmp / "deep.yaml"))),
        "chain, 28 000 nodes, valid": (tmp / "long.yaml", chain.format(
            p=str(tmp / "long.yaml"))),
        ".mat 1x1 double, 3.9 GiB data element": (tmp / "bomb.mat", load.format(
            p=str(tmp / "bomb.mat"), port=(1,))),
        ".npz member declaring 3.9 GiB, port (4,)": (tmp / "bomb.npz", load.format(
            p=str(tmp / "bomb.npz"), port=(4,))),
        ".bin 96 MiB, decoded": (tmp / "capture.bin", (
            "from radar.ti_capture import TiBinLayout, read_ti_bin; read_ti_bin("
            f"{str(tmp / 'capture.bin')!r}, TiBinLayout.parse('samples=256,chirps=128,rx=4'))")),
        "sweep, 120 000 aliases of 400 KB": (tmp / "aliases.yaml", (
            "from radarsnn.sweep.spec import load_spec; "
            f"load_spec({str(tmp / 'aliases.yaml')!r})")),
        "sweep, 33 axes x 2 values, planned": (tmp / "grid.yaml", (
            "from radarsnn.sweep.run import plan_cells; from radarsnn.sweep.spec import "
            f"load_spec; plan_cells(load_spec({str(tmp / 'grid.yaml')!r}))")),
    }


def main(argv: list[str] | None = None) -> int:
    """Print one line per case: bytes, seconds, peak growth (MiB), outcome."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cap-mib", type=int, default=6144)
    p.add_argument("--timeout-s", type=float, default=120.0)
    p.add_argument("--code", type=Path, default=ROOT, help="the checkout to measure")
    args = p.parse_args(argv)
    env = {**os.environ, "PYTHONPATH": str(args.code.resolve()), "OPENBLAS_NUM_THREADS": "1"}

    def run(call: str, cwd: str, bound: float | None) -> str:
        """The row of one call: seconds, peak growth, outcome, and the bound it keeps."""
        code = _CHILD.format(call=call, cap=args.cap_mib << 20)
        try:
            done = subprocess.run([sys.executable, "-c", code], capture_output=True,
                                  text=True, timeout=args.timeout_s, env=env, cwd=cwd)
            seconds, growth, end = json.loads(done.stdout.splitlines()[-1])
        except subprocess.TimeoutExpired:
            return f"over {args.timeout_s:.0f} s (killed)"
        except (IndexError, ValueError):
            return f"child failed: {done.stderr.strip().splitlines()[-1:]}"
        kept = "" if bound is None else (
            f"  [bound {bound:g} s: {'ok' if seconds < bound else 'SLOW'}]")
        return f"{seconds:9.4f} s {growth:8.0f} MiB{kept}  {end}"

    with tempfile.TemporaryDirectory() as tmp:
        for name, (path, call) in cases(Path(tmp)).items():
            print(f"{name:42s} {path.stat().st_size:>10d} B "
                  f"{run(call, tmp, BOUNDS_S.get(name))}", flush=True)
    from bombs import reader_bombs

    print("\nthe suite's bomb per reader (tests/bombs.py)")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (call, _) in reader_bombs(Path(tmp)).items():
            print(f"{name:42s} {run(call, tmp, READER_BOMB_BOUND_S)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
