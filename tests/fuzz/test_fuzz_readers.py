"""Fuzz the readers of users' files and the sweep planner for amplification.

Three classes, each with the contract of the suite (a correct result or a typed error naming
the culprit) plus a bound on time and memory:

* **bounded decompression for every reader** — one small bomb per reader (``.npz`` and
  ``.mat`` inputs, ``.npy`` inputs, TI ``.bin``, an artifact's ``arrays.npz``, classifier
  weights, a folder frame source), all read in one child interpreter under an
  address-space cap: each must be refused in well under a second without reserving more
  than the cap (they declare or inflate to 2-4 GiB from at most 4 MB); and hypothesis over
  the bombs' declared sizes and shapes in-process, peak memory growth ≤ 256 MiB;
* **grid and alias amplification in sweeps** — random grids (up to 40 axes of up to 12
  values), frame counts and alias fan-outs: parsing either refuses with a
  ``CompileError`` or gives a spec whose points can be planned, within bounded time;
* **hostile folder sources** — random patterns (hostile strings, globs, absolute and
  climbing paths) and folders holding FIFOs, sub-folders, forged headers, object arrays
  and damaged files.
"""

from __future__ import annotations

import json
import os
import time

import numpy as np
from bombs import (
    deflate_zeros,
    mat_bomb,
    mat_uncompressed_bomb,
    mat_v4_bomb,
    npy_header,
    npz_bomb,
    zip_deflated,
)
from capped import run_capped
from fuzz_support import HOSTILE_STRINGS, bounded_outcome, budget, outcome
from hypothesis import given
from hypothesis import strategies as st

_GIB = 1 << 30


def _cases(tmp) -> dict[str, tuple[str, str]]:
    """Reader -> (the call, what its error must say), the bomb files written into ``tmp``."""
    files = {
        "in.npz": npz_bomb((int(3.9 * _GIB) // 8,)),
        "lying.npz": zip_deflated("x.npy", deflate_zeros(3 * _GIB, raw=True, prefix=npy_header(
            (2,))), len(npy_header((2,))) + 16),  # the zip entry says 16 bytes of data
        "framed.npz": zip_deflated("x.npy", deflate_zeros(_GIB, raw=True, prefix=npy_header(
            (int(4.1 * _GIB) // 32, 4))), 1 << 20),  # frames of the port, over 4 GiB
        "data.mat": mat_bomb(int(3.9 * _GIB)),
        "dims.mat": mat_bomb(0, dims_bytes=3 * _GIB),
        "tag.mat": mat_uncompressed_bomb(4 * _GIB - 64),
        "v4.mat": mat_v4_bomb(16_000, 16_000),
        "in.npy": npy_header((10**12,)) + bytes(16),
        "art.npz": npz_bomb((int(3.9 * _GIB) // 8,)),
    }
    for name, data in files.items():
        (tmp / name).write_bytes(data)
    with (tmp / "big.bin").open("wb") as f:
        f.truncate(512 << 20)
    (tmp / "frames").mkdir()
    for i in range(2):
        np.save(tmp / "frames" / f"f{i}.npy", np.zeros(4))
    (tmp / "frames" / "f2.npy").write_bytes(npy_header((10**12,)) + bytes(16))
    arrays = ("from radarsnn.cli.arrays import load_arrays; "
              "load_arrays([{p!r}], ['x'], 'chain c', shapes={{'x': {port}}})")
    return {
        "npz input": (arrays.format(p=str(tmp / "in.npz"), port=(4,)),
                      "but the port takes (4,)"),
        "npz member inflating past its size": (
            arrays.format(p=str(tmp / "lying.npz"), port=(4,)), "not a readable .npz archive"),
        "npz framed input over 4 GiB": (arrays.format(p=str(tmp / "framed.npz"), port=(4,)),
                                        "over the limit of 4294967296"),
        "mat data element": (arrays.format(p=str(tmp / "data.mat"), port=(1,)),
                             "inflates to more than"),
        "mat dimensions": (arrays.format(p=str(tmp / "dims.mat"), port=(1,)),
                           "not a readable .mat"),
        "mat uncompressed tag": (arrays.format(p=str(tmp / "tag.mat"), port=(1,)),
                                 "holds a data element of 4294967232 bytes"),
        "mat v4 header": (arrays.format(p=str(tmp / "v4.mat"), port=(16_000, 16_000)),
                          "but the file holds 30"),
        "npy input": (arrays.format(p=str(tmp / "in.npy"), port=(4,)), "over the limit"),
        "bin capture": ("from radarsnn.cli.arrays import load_arrays; load_arrays("
                        f"[{str(tmp / 'big.bin')!r}], ['x'], 'c', bin_layout='samples=256,"
                        "chirps=128,rx=4', shapes={'x': (4, 64, 256)})", "but the port takes"),
        "artifact arrays.npz": ("from pathlib import Path; from backends.npz_reader import "
                                f"read_npz; read_npz(Path({str(tmp / 'art.npz')!r})."
                                "read_bytes(), Path('arrays.npz'))", "is compressed"),
        "classifier weights": ("from ir.classifier_forward.weights import load_weights; "
                               "from ir.ops.classify import Classifier; load_weights(Classifier."
                               f"model_construct(weights={str(tmp / 'in.npz')!r}), (16, 16), "
                               "'cls')", "over the limit"),
        "folder frame": ("from radarsnn.sweep.frames import load_frames; from radarsnn.sweep."
                         "sections import FolderFrames; load_frames(FolderFrames(source='folder', "
                         f"path='frames'), {str(tmp)!r}, 0, 1, calibration=True)",
                         "over the limit"),
    }


def test_every_reader_refuses_a_small_bomb_quickly_in_bounded_memory(tmp_path):
    cases = _cases(tmp_path)
    body = """
        import json, time
        from ir.errors import RadarSNNError
        out = {}
        for name, code in json.loads(CASES).items():
            start = time.perf_counter()
            try:
                exec(code, {})
                out[name] = ["read", "", 0.0]
            except RadarSNNError as err:
                out[name] = [type(err).__name__, str(err), time.perf_counter() - start]
            except BaseException as err:
                out[name] = [type(err).__name__, str(err)[:300], time.perf_counter() - start]
        print(json.dumps(out))
        """.replace("CASES", repr(json.dumps({k: c for k, (c, _) in cases.items()})))
    done = run_capped("import numpy, scipy.io, radarsnn.cli.arrays, radarsnn.sweep.frames, "
                      "backends.npz_reader", body, headroom_bytes=_GIB, timeout_s=120)
    assert done.returncode == 0, done.stderr[-3000:]
    results = json.loads(done.stdout.splitlines()[-1])
    for name, (_, why) in cases.items():
        kind, text, seconds = results[name]
        assert kind in ("RadarConfigError", "RadarSNNError", "ArtifactError", "IRError"), (
            name, kind, text)
        assert why in text, (name, text)
        assert "\n" not in text and seconds < 3.0, (name, seconds)


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
    start = time.perf_counter()
    got = bounded_outcome(lambda: load_arrays([str(path)], ["x"], "chain c",
                                              shapes={"x": port}), [str(path)],
                          max_growth=256 << 20)
    assert got is None and time.perf_counter() - start < 2.0


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
    start = time.perf_counter()
    parsed = bounded_outcome(lambda: parse_spec(spec), ["grid", "points", "cells", "bytes",
                                                        "aliases"])
    assert time.perf_counter() - start < 2.0
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

    start = time.perf_counter()
    batch = bounded_outcome(use, culprits)
    assert time.perf_counter() - start < 5.0
    if batch is not None:
        assert all(isinstance(a, np.ndarray) and a.dtype != object for a in batch.arrays)
