"""Digests of the artifacts of every example chain and demo scene, for every built-in profile.

A change that must not change behaviour (a restructuring) keeps every saved artifact
byte-identical.  Record the digests before the change, check them after::

    python benchmarks/artifact_digests.py --record /tmp/digests.json   # before
    python benchmarks/artifact_digests.py --check /tmp/digests.json    # after: exit 1 on a change

Compiled: each chain of ``examples/chains/`` (calibrated as ``radarsnn compile`` does
without ``-c``: on synthetic noise, seed 0) and the range-Doppler chain of each demo scene
(``seed003``, ``carrada``) calibrated on the demo's calibration frame (seed 1000), each
for every profile of ``compiler/hardware/profiles``.  Each artifact file's SHA-256 is
listed by relative path (a compile that raises: its error message); ``--only NAME``
restricts to the cases whose name contains it.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this source tree, not whatever an installed radarsnn points at
PROFILES = ("loihi", "loihi2", "spinnaker2", "unbounded")
SCENES = ("seed003", "carrada")


def _cases():
    """(name, graph, calibration inputs or None) for every example chain and demo scene."""
    from compiler.calibration import synthetic_inputs
    from compiler.chains import range_doppler_chain
    from ir import Graph
    from radar.config import preset
    from radar.scene import SCENE_PRESETS, simulate_frame
    from radarsnn.demo.scenes import CALIBRATION_SEED_OFFSET

    for path in sorted((ROOT / "examples" / "chains").glob("*.yaml")):
        graph = Graph.from_yaml(path)
        yield path.stem, graph, synthetic_inputs(graph, seed=0)
    for name in SCENES:
        config = preset(name)
        frame = simulate_frame(config, SCENE_PRESETS[name](), seed=CALIBRATION_SEED_OFFSET)
        yield f"demo-{name}", range_doppler_chain(config), {"adc": frame.adc}


def _digests(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def digests(only: str | None = None) -> dict[str, dict[str, str]]:
    """``{case/profile: {file: sha256}}`` for every case (containing ``only``, if given)."""
    from backends.program_artifact import save_program
    from compiler.compile import compile_graph
    from ir.errors import RadarSNNError

    out: dict[str, dict[str, str]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, graph, calibration in _cases():
            for profile in PROFILES:
                key = f"{name}/{profile}"
                if only and only not in key:
                    continue
                start = time.perf_counter()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        program = compile_graph(graph, profile, calibration_inputs=calibration)
                except RadarSNNError as err:  # a chain that does not fit: its message is kept
                    out[key] = {"error": f"{type(err).__name__}: {err}"}
                else:
                    out[key] = _digests(save_program(program, Path(tmp) / key.replace("/", "__")))
                print(f"{key:40s} {len(out[key]):3d} files  {time.perf_counter() - start:6.1f} s",
                      file=sys.stderr, flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--record", type=Path, help="write the digests to this JSON file")
    group.add_argument("--check", type=Path, help="compare with the digests in this file")
    parser.add_argument("--only", help="only the cases whose name/profile contains this")
    args = parser.parse_args(argv)
    found = digests(args.only)
    if args.record:
        args.record.write_text(json.dumps(found, indent=1, sort_keys=True) + "\n")
        print(f"recorded {len(found)} artifacts in {args.record}")
        return 0
    expected = json.loads(args.check.read_text())
    changed = [k for k in found if found[k] != expected.get(k)]
    for key in changed:
        files = sorted(f for f in {*found[key], *expected.get(key, {})}
                       if found[key].get(f) != expected.get(key, {}).get(f))
        print(f"CHANGED {key}: {', '.join(files)}")
    print(f"{len(found) - len(changed)} of {len(found)} artifacts byte-identical")
    return 1 if changed else 0


if __name__ == "__main__":
    raise SystemExit(main())
