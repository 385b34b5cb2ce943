"""Fuzz the readers of users' files and the sweep planner for amplification.

Three classes, each with the contract of the suite (a correct result or a typed error naming
the culprit) plus a bound on memory (what each costs in time is measured by
``benchmarks/hostile_inputs.py``: wall-clock bounds do not belong in tests):

* **bounded decompression for every reader** — one small bomb per reader (``.npz`` and
  ``.mat`` inputs, ``.npy`` inputs, TI ``.bin``, an artifact's ``arrays.npz``, classifier
  weights, a folder frame source), all read in one child interpreter under an
  address-space cap: each must be refused without reserving more than the cap (they
  declare or inflate to 2-4 GiB from at most 4 MB); and hypothesis over
  the bombs' declared sizes and shapes in-process, peak memory growth ≤ 256 MiB;
* **grid and alias amplification in sweeps** — random grids (up to 40 axes of up to 12
  values), frame counts and alias fan-outs: parsing either refuses with a
  ``CompileError`` or gives a spec whose points can be planned, in bounded memory;
* **hostile folder sources** — random patterns (hostile strings, globs, absolute and
  climbing paths) and folders holding FIFOs, sub-folders, forged headers, object arrays
  and damaged files.
"""

from __future__ import annotations

import json
import os

import numpy as np
from bombs import (
    deflate_zeros,
    mat_bomb,
    mat_uncompressed_bomb,
    npy_header,
    npz_bomb,
    reader_bombs,
    zip_deflated,
)
from capped import run_capped
from fuzz_support import HOSTILE_STRINGS, bounded_outcome, budget, outcome
from hypothesis import given
from hypothesis import strategies as st

_GIB = 1 << 30


def test_every_reader_refuses_a_small_bomb_in_bounded_memory(tmp_path):
    # the time each refusal takes (well under a second) is measured by
    # benchmarks/hostile_inputs.py; here the address-space cap is the check
    cases = reader_bombs(tmp_path)
    body = """
        import json
        from ir.errors import RadarSNNError
        out = {}
        for name, code in json.loads(CASES).items():
            try:
                exec(code, {})
                out[name] = ["read", ""]
            except RadarSNNError as err:
                out[name] = [type(err).__name__, str(err)]
            except BaseException as err:
                out[name] = [type(err).__name__, str(err)[:300]]
        print(json.dumps(out))
        """.replace("CASES", repr(json.dumps({k: c for k, (c, _) in cases.items()})))
    done = run_capped("import numpy, scipy.io, radarsnn.cli.arrays, radarsnn.sweep.frames, "
                      "backends.npz_reader", body, headroom_bytes=_GIB, timeout_s=120)
    assert done.returncode == 0, done.stderr[-3000:]
    results = json.loads(done.stdout.splitlines()[-1])
    for name, (_, why) in cases.items():
        kind, text = results[name]
        assert kind in ("RadarConfigError", "RadarSNNError", "ArtifactError", "IRError"), (
            name, kind, text)
        assert why in text, (name, text)
        assert "\n" not in text, (name, text)


_DECLARED = st.sampled_from([1 << 20, 64 << 20, _GIB, 3 * _GIB, int(3.9 * _GIB)])


def _framed_bomb(declared: int, port: tuple) -> bytes:
    """Frames of the port inflating to ``declared`` bytes (a 64 MiB one is a valid shape,
    read to its end, where its CRC is wrong); over 4 GiB, its header alone refuses it."""
    if declared <= 64 << 20:
        return npz_bomb((declared // (8 * int(np.prod(port))), *port))
    head = npy_header((int(4.1 * _GIB) // (8 * int(np.prod(port))), *port))
    return zip_deflated("x.npy", deflate_zeros(1 << 20, raw=True, prefix=head), 1 << 20)


@given(declared=_DECLARED, kind=st.sampled_from(["npz", "npz-framed", "mat", "mat-tag"]),
       port=st.sampled_from([(1,), (4,), (2, 3), (16, 8)]))
@budget(0.05)
def test_bombs_of_any_size_cost_what_the_port_takes(tmp_path_factory, declared, kind, port):
    import scipy.io  # noqa: F401 - imported before the clock starts, as radar is below

    import radar.readers  # noqa: F401
    from radarsnn.cli.arrays import load_arrays

    tmp = tmp_path_factory.mktemp("bomb")
    path = tmp / f"x.{kind.partition('-')[0]}"
    data = {"npz": lambda: npz_bomb((declared // 8,)),
            "npz-framed": lambda: _framed_bomb(declared, port),
            "mat": lambda: mat_bomb(declared),
            "mat-tag": lambda: mat_uncompressed_bomb(declared)}[kind]()
    path.write_bytes(data)
    got = bounded_outcome(lambda: load_arrays([str(path)], ["x"], "chain c",
                                              shapes={"x": port}), [str(path)],
                          max_growth=256 << 20)
    assert got is None


# -- sweeps: grids and aliases ---------------------------------------------------------------

def _axes():
    from compiler.compile import EXTRA_OPTIONS
    from radarsnn.sweep.spec import NAMED_AXES

    return sorted(set(EXTRA_OPTIONS) | set(NAMED_AXES) - {"chain"})


_CHAIN = {"name": "c", "nodes": [{"id": "x", "op": "input", "shape": {"range": 4}},
                                 {"id": "o", "op": "output", "input": "x"}]}


@given(lengths=st.lists(st.integers(1, 12), min_size=0, max_size=40),
       n_frames=st.sampled_from([1, 25, 10**4, 10**7, 10**12]),
       per_cell=st.sampled_from([1, 25, 10**6]),
       fan=st.sampled_from([0, 1, 100, 10**4, 10**5]), big=st.sampled_from([1, 1000, 10**6]))
@budget(0.2)
def test_grids_and_aliases_are_refused_or_planned_in_bounded_time(lengths, n_frames,
                                                                  per_cell, fan, big):
    from radarsnn.sweep.spec import MAX_SWEEP_CELLS, MAX_SWEEP_POINTS, parse_spec

    shared = "v" * big  # one object referred to `fan` times: what YAML aliases build
    grid = {a: list(range(n)) for a, n in zip(_axes(), lengths, strict=False)}
    spec = {"name": "t", "chains": {"a": _CHAIN}, "grid": grid,
            "options": {"input_bounds": {"x": [shared] * fan}},
            "frames": {"source": "scene", "n_frames": n_frames, "frames_per_cell": per_cell}}
    parsed = bounded_outcome(lambda: parse_spec(spec), ["grid", "points", "cells", "bytes",
                                                        "aliases"])
    if parsed is not None:
        n_points = parsed.n_points()
        assert n_points <= MAX_SWEEP_POINTS
        assert n_points * len(parsed.slices()) <= MAX_SWEEP_CELLS
        if n_points <= 64:
            assert len(parsed.points()) == n_points


# -- hostile folder sources -------------------------------------------------------------------

_PATTERNS = st.one_of(st.sampled_from(HOSTILE_STRINGS), st.sampled_from(
    ["*.npy", "*", "?", "f[0-9].npy", "sub/*.npy", "**/*.npy", "../*", "/etc/*", "", "*" * 500,
     "a*" * 9, "[", "[!a].npy", "x\0.npy", "C:*.npy", "./*.npy", "*.npy/", "\\*.npy"]),
    st.text(alphabet="*?[]!/.a-\\", max_size=12))

_FILES = st.sampled_from(["good", "good", "fifo", "dir", "huge", "object", "truncated", "text",
                          "empty", "npz", "symlink-fifo"])


def _write(folder, name: str, kind: str) -> None:
    path = folder / name
    if kind == "good":
        np.save(path, np.arange(4.0))
    elif kind in ("fifo", "symlink-fifo"):
        target = folder / f".{name}.fifo" if kind == "symlink-fifo" else path
        os.mkfifo(target)
        if kind == "symlink-fifo":
            os.symlink(target, path)
    elif kind == "dir":
        path.mkdir()
    elif kind == "huge":
        path.write_bytes(npy_header((10**12,)) + bytes(16))
    elif kind == "object":
        np.save(path, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    elif kind == "truncated":
        path.write_bytes(npy_header((100,)) + bytes(16))
    elif kind == "text":
        path.write_text("not an array")
    elif kind == "empty":
        path.write_bytes(b"")
    else:
        np.savez(path, x=np.zeros(4))


@given(pattern=_PATTERNS, kinds=st.lists(_FILES, min_size=1, max_size=5),
       calibration=st.integers(1, 3), labels=st.booleans())
@budget(0.2)
def test_hostile_folder_sources_are_typed_errors(tmp_path_factory, pattern, kinds,
                                                 calibration, labels):
    from radarsnn.sweep.frames import folder_files, load_frames
    from radarsnn.sweep.spec import parse_spec

    tmp = tmp_path_factory.mktemp("frames")
    for i, kind in enumerate(kinds):
        _write(tmp, f"f{i}.npy", kind)
    if labels:
        np.save(tmp / "labels.npy", np.arange(len(kinds)))
    spec = {"name": "t", "chains": {"a": _CHAIN}, "frames": {
        "source": "folder", "path": ".", "pattern": pattern,
        "calibration_frames": calibration, **({"labels": "labels.npy"} if labels else {})}}
    culprits = ["pattern", str(tmp), *[f"f{i}.npy" for i in range(len(kinds))], "labels"]
    parsed = outcome(lambda: parse_spec({**spec, "base_dir": str(tmp)}), culprits)
    if parsed is None:
        return
    source = parsed.frames

    def use():
        scored, cal = folder_files(source, tmp)
        load_frames(source, tmp, 0, len(cal), calibration=True)
        return load_frames(source, tmp, 0, len(scored))

    batch = bounded_outcome(use, culprits)
    if batch is not None:
        assert all(isinstance(a, np.ndarray) and a.dtype != object for a in batch.arrays)
