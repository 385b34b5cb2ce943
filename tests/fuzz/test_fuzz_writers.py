"""Fuzz: every writer of the command line keeps a user's files and refuses odd output paths.

* **user files**: files and folders a user keeps beside or inside an output — top level,
  nested (``networks/0/…``, ``__pycache__/…``, ``figures/…``), ``*.tmp`` files and
  folders, hidden names — survive, byte for byte, a write and two re-writes by each writer
  (``compile -o``, ``run -o``, ``emit``, ``export-nir``, ``sweep --out``, ``demo --out``).
  A writer either keeps them (and succeeds) or refuses in one line naming its output
  (``compile -o``: an artifact folder holds only what a save wrote).
* **odd paths**: a device (a private ``null`` node like ``/dev/null``), a pipe, a folder
  given for a file (a file for a folder), a NUL byte, an empty name, a trailing ``/``, a
  name too long, a path through a file: one ``error:`` line, nothing created (not even
  beside the device), nothing changed.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from faults import device_node, fault_chain, listing, tree_bytes
from fuzz_support import budget
from hypothesis import example, given, note
from hypothesis import strategies as st

from backends import save_program
from compiler.compile import compile_graph
from radarsnn.cli import main

GRAPH, X = fault_chain("fuzz-writers")
MAPS = {"name": "tiny-os", "nodes": [
    {"id": "rd", "op": "input", "shape": {"range": 16, "doppler": 8}, "domain": "db"},
    {"id": "det", "op": "cfar", "input": "rd", "kind": "os", "axes": ["range", "doppler"],
     "guard": [1, 1], "train": [2, 1], "k": 20, "alpha": 1.1, "edge": ["clip", "wrap"]},
    {"id": "out", "op": "output", "input": "det"}]}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A chain file, its compiled program, an input, and a one-point sweep on four maps."""
    root = tmp_path_factory.mktemp("inputs")
    chain = root / "chain.yaml"
    chain.write_text(yaml.safe_dump(GRAPH.to_dict(), sort_keys=False))
    np.save(root / "x.npy", X["a"])
    art = save_program(compile_graph(GRAPH, target="loihi2", calibration_inputs=X), root / "art")
    rng = np.random.default_rng(3)
    (root / "maps").mkdir()
    for i in range(4):
        np.save(root / "maps" / f"m{i}.npy", rng.normal(50.0, 3.0, (16, 8)) + 40.0 * (i >= 2))
    spec = root / "sweep.yaml"
    spec.write_text(yaml.safe_dump({
        "name": "w", "chains": {"os": MAPS}, "grid": {"time_steps": [8]},
        "options": {"cfar_quantiles": [0.0, 1.0]},
        "frames": {"source": "folder", "path": "maps", "calibration_frames": 2,
                   "frames_per_cell": 2},
        "metrics": [{"name": "cfar"}], "figures": ["pareto"]}, sort_keys=False))
    return {"chain": str(chain), "art": str(art), "x": str(root / "x.npy"), "spec": str(spec)}


#: writer -> (command line writing into the folder ``o``, folders a user's files go in,
#: folders that exist only after the first write, whether foreign files are refused).
WRITERS = {
    "compile": (lambda i, o: ["compile", i["chain"], "-o", f"{o}/art", "-q"],
                [""], ["art"], True),
    "run": (lambda i, o: ["run", i["art"], "-i", i["x"], "-o", f"{o}/out.npz", "-q"],
            [""], [], False),
    "emit": (lambda i, o: ["emit", i["art"], "-o", o, "--name", "pkg"], [""], ["pkg"], False),
    "export-nir": (lambda i, o: ["export-nir", i["art"], "-o", f"{o}/x.nir", "-q"],
                   [""], [], False),
    "sweep": (lambda i, o: ["sweep", i["spec"], "--scheduler", "sync", "--out", o, "--quiet"],
              [""], ["figures"], False),
    "demo": (lambda i, o: ["demo", "--preset", "seed003", "--conventional-only", "--out", o,
                           "-q"], [""], [], False),
}
#: Examples per writer (the sweep and the demo take a second or more a write: one example,
#: the demo one re-write).
EXAMPLES = {"sweep": 0.0, "demo": 0.0}
REWRITES = {"demo": 1}

#: A writer's temporary (``.NAME.PID-TOKEN.tmp`` and its folder kinds).
TEMPORARY = re.compile(r"\.\d+-[0-9a-f]{8}\.(tmp|saving|old)$")
_NAME = st.from_regex(r"[a-z][a-z0-9_]{0,7}(\.tmp|\.txt|\.npy|\.bak)?", fullmatch=True).filter(
    lambda n: n not in ("art", "pkg", "figures"))  # the outputs' own names
_PLACES = st.sampled_from(["", "networks/", "networks/0/", "sub/deep/", "__pycache__/",
                           "figures/", "x.tmp/", "."])
USER_FILES = st.dictionaries(st.builds(lambda d, n: f"{d}{n}" if d != "." else f".{n}",
                                       _PLACES, _NAME),
                             st.binary(max_size=64), min_size=1, max_size=6)


def _place(root: Path, files: dict[str, bytes]) -> dict[str, bytes]:
    placed = {}
    for rel, data in files.items():
        path = root / rel
        if any(p.is_file() for p in (root / rel).parents if p != root):
            continue  # a drawn file has the name of a drawn folder
        if path.exists():
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        placed[str(path)] = data
    return placed


def _write(argv: list[str], capsys, refuses: bool, placed: bool) -> None:
    code = main(argv)
    err = capsys.readouterr().err
    if refuses and placed:
        assert code == 1, err
        assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, err
    else:
        assert code == 0, err


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_every_writer_keeps_a_users_files(inputs, tmp_path_factory, capsys, writer):
    command, places, after, refuses = WRITERS[writer]

    @budget(EXAMPLES.get(writer, 0.005))
    @given(user=USER_FILES, inside=USER_FILES)
    @example(user={".hidden": b"h", "__pycache__/helper.pyc": b"p", "notes.txt": b"n"},
             inside={"networks/0/calib.npy": b"c", "networks/readme.txt": b"r",  # names an
                     "scratch.tmp": b"t", "x.tmp/a": b""})  # artifact's check once let pass
    def check(user: dict[str, bytes], inside: dict[str, bytes]) -> None:
        root = tmp_path_factory.mktemp(writer)
        argv = command(inputs, str(root))
        mine = {}
        for place in places:
            mine |= _place(root / place, user)
        _write(argv, capsys, refuses=False, placed=False)  # beside the output: never refused
        for place in after:
            mine |= _place(root / place, inside)
        note(f"{writer}: {sorted(mine)}")
        for _ in range(REWRITES.get(writer, 2)):
            _write(argv, capsys, refuses, placed=any(
                p.startswith(str(root / a) + "/") for a in after for p in mine))
            assert {p: Path(p).read_bytes() for p in mine} == mine
        assert not [p for p in listing(root) if TEMPORARY.search(p)]  # none left behind

    check()


#: file writers: the command line writing to the file ``path``
FILE_WRITERS = {
    "run": lambda i, p: ["run", i["art"], "-i", i["x"], "-o", p, "-q"],
    "export-nir": lambda i, p: ["export-nir", i["art"], "-o", p, "-q"],
    "schema": lambda i, p: ["schema", "-o", p],
    "report --core-map": lambda i, p: ["report", i["art"], "--core-map", p],
}
#: folder writers: the command line writing the folder ``path``
FOLDER_WRITERS = {
    "compile": lambda i, p: ["compile", i["chain"], "-o", p, "-q"],
    "emit": lambda i, p: ["emit", i["art"], "-o", p, "--name", "pkg"],
    "sweep": lambda i, p: ["sweep", i["spec"], "--scheduler", "sync", "--out", p, "--quiet"],
    "demo": lambda i, p: ["demo", "--preset", "seed003", "--conventional-only", "--out", p,
                          "-q"],
}


def _odd_paths(root: Path, folder: bool) -> list[str]:
    fifo = root / "fifo"
    os.mkfifo(fifo)
    (root / "dir").mkdir()
    (root / "file").write_bytes(b"a user's file")
    device = device_node(root)  # as /dev/null (never the real one: a bug would replace it)
    paths = [str(fifo), "x\0y", str(root / "file" / "x"), str(root / ("x" * 300)),
             *([str(device)] if device else [])]
    return paths + ([str(root / "file")] if folder else [str(root / "dir"), "", f"{root}/o/"])


@pytest.mark.parametrize("writer", sorted({**FILE_WRITERS, **FOLDER_WRITERS}))
def test_odd_output_paths_are_refused_in_one_line(inputs, tmp_path, capsys, monkeypatch,
                                                  writer):
    folder = writer in FOLDER_WRITERS
    command = (FOLDER_WRITERS if folder else FILE_WRITERS)[writer]
    monkeypatch.chdir(tmp_path)
    paths = [p for p in _odd_paths(tmp_path, folder)  # `run -o DIR` writes DIR.npz beside it
             if not (writer == "run" and p == str(tmp_path / "dir"))]
    before = tree_bytes(tmp_path), listing(tmp_path)
    for path in paths:
        code = main(command(inputs, path))
        err = capsys.readouterr().err
        assert code in (1, 2), (path, err)
        assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, (path, err)
    assert (tree_bytes(tmp_path), listing(tmp_path)) == before  # no null.npz beside the device
