"""Writers delete only what they wrote, are atomic, and refuse odd output paths.

Issue "Hostile input, round three", items 1-4 and 10: ``emit`` removed any folder holding a
``names.json`` with the user's files in it, and a re-emit the files a user had added;
``compile -o`` deleted a user's ``*.tmp`` files and folders and anything nested under
``networks/``; a SIGKILL during ``emit`` over a good package lost it (26 of 30 kills);
``export-nir`` left a truncated ``.nir`` on a full disk, ``-o /dev/null`` wrote
``/dev/null.report.json`` (``run``: ``/dev/null.npz``) and a NUL byte was a traceback;
sweep figure names such as ``../../X`` wrote outside ``--out``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from faults import device_node, fault_chain, kill_while_saving, listing, tree_bytes

from backends import save_program
from backends.emit import emit_numpy
from compiler.compile import compile_graph
from ir.errors import ArtifactError, CompileError
from radarsnn.cli import main

GRAPH, X = fault_chain("owner")


@pytest.fixture(scope="module")
def programs():
    two = compile_graph(GRAPH, target="loihi2", calibration_inputs=X, motifs={"w": "time"})
    one = compile_graph(GRAPH, target="loihi2", calibration_inputs=X)
    return two, one


def _user_files(root: Path) -> dict[str, bytes]:
    """A user's files at ``root``: top level, nested, ``*.tmp`` files and folders."""
    files = {"notes.txt": b"mine", "data/x.npy": b"\x93NUMPY", "scratch.tmp": b"keep",
             "cache.tmp/part": b"half", "networks/README.txt": b"readme",
             "networks/0/calib.npy": b"calib"}
    for rel, data in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_bytes(data)
    return files


def _kept(root: Path, files: dict[str, bytes]) -> bool:
    return all((root / rel).read_bytes() == data for rel, data in files.items())


def test_emit_keeps_a_users_files_and_replaces_only_what_it_wrote(programs, tmp_path):
    two, one = programs
    pkg = emit_numpy(two, tmp_path, name="pkg")
    mine = _user_files(pkg)
    (pkg / "__pycache__").mkdir()
    (pkg / "__pycache__" / "program.cpython-311.pyc").write_bytes(b"stale bytecode")
    (pkg / "__pycache__" / "helper.cpython-311.pyc").write_bytes(b"a user's module")
    emit_numpy(one, tmp_path, name="pkg")
    assert _kept(pkg, mine)
    fresh = emit_numpy(one, tmp_path / "fresh", name="pkg")
    ours = {k: v for k, v in tree_bytes(pkg).items() if k not in mine and "__pycache__" not in k}
    assert ours == tree_bytes(fresh)  # exactly a fresh package besides the user's files
    assert os.listdir(pkg / "__pycache__") == ["helper.cpython-311.pyc"]  # stale one removed
    assert "network_1.py" not in os.listdir(pkg)  # what the earlier emit wrote is replaced
    names = json.loads((pkg / "names.json").read_text())
    assert "notes.txt" not in names["files"] and "program.py" in names["files"]
    assert sorted(os.listdir(tmp_path)) == ["fresh", "pkg"]


def test_emit_refuses_a_users_folder_or_a_name_clash(programs, tmp_path):
    _, one = programs
    own = tmp_path / "pkg"
    own.mkdir()
    (own / "names.json").write_text('{"mine": 1}')  # a user's names.json is not emit's
    (own / "notes.txt").write_text("mine")
    before = tree_bytes(own)
    with pytest.raises(ArtifactError, match="not a generated package"):
        emit_numpy(one, tmp_path, name="pkg")
    assert tree_bytes(own) == before
    pkg = emit_numpy(one, tmp_path, name="gen")
    (pkg / "network_1.py").write_text("# a user's file with a name emit now writes")
    two = compile_graph(GRAPH, target="loihi2", calibration_inputs=X, motifs={"w": "time"})
    before = tree_bytes(pkg)
    with pytest.raises(ArtifactError, match="network_1.py.*move it away"):
        emit_numpy(two, tmp_path, name="gen")
    assert tree_bytes(pkg) == before and sorted(os.listdir(tmp_path)) == ["gen", "pkg"]


@pytest.mark.parametrize("extra", ["scratch.tmp", "cache.tmp/part", "networks/README.txt",
                                   "networks/0/calib.npy", "networks/7/manifest.json"])
def test_compile_refuses_to_delete_a_users_tmp_or_nested_files(programs, tmp_path, extra):
    two, one = programs
    folder = save_program(two, tmp_path / "art")
    (folder / extra).parent.mkdir(parents=True, exist_ok=True)
    (folder / extra).write_bytes(b"mine")
    before = tree_bytes(folder)
    with pytest.raises(ArtifactError, match=f"{extra.split('/')[0]}.*move them away"):
        save_program(one, folder)
    assert tree_bytes(folder) == before and os.listdir(tmp_path) == ["art"]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_sigkill_while_emitting_leaves_the_old_or_the_new_package(programs, tmp_path):
    refs = [tree_bytes(emit_numpy(p, tmp_path / f"ref{i}", name="target"))
            for i, p in enumerate(programs)]

    def emit(program, target: Path) -> Path:
        return emit_numpy(program, target.parent, name=target.name)

    def check(target: Path) -> str:
        files = tree_bytes(target)
        assert files.pop("notes.txt") == b"mine"  # the user's file survives every kill
        return f"v{refs.index(files)}"  # a complete package, else ValueError

    emit(programs[0], tmp_path / "target")
    (tmp_path / "target" / "notes.txt").write_bytes(b"mine")
    seen = kill_while_saving(tmp_path, list(programs), emit, check, kills=8, seed=12)
    assert set(seen) <= {"v0", "v1"}
    emit(programs[1], tmp_path / "target")  # the next emit removes what the kills left
    assert sorted(os.listdir(tmp_path)) == ["ref0", "ref1", "target"]


@pytest.fixture(scope="module")
def files(programs, tmp_path_factory):
    root = tmp_path_factory.mktemp("cli")
    np.save(root / "x.npy", X["a"])
    return save_program(programs[0], root / "art"), root / "x.npy"


def test_export_nir_on_a_full_disk_keeps_the_previous_pair(files, tmp_path, disk_full, capsys):
    art, _ = files
    out = tmp_path / "x.nir"
    argv = ["export-nir", str(art), "-o", str(out), "-q"]
    assert main(argv) == 0
    before = tree_bytes(tmp_path)
    for free in (0, 100, 3000):
        with disk_full(free=free):
            assert main(argv) == 1
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and str(out) in err and "No space" in err
        assert tree_bytes(tmp_path) == before  # no truncated .nir, no temporary


@pytest.mark.parametrize("command", ["export-nir", "run"])
def test_output_paths_that_are_no_file_are_refused_in_one_line(files, tmp_path, capsys,
                                                                command):
    art, x = files
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    (tmp_path / "dir").mkdir()
    device = device_node(tmp_path)  # as /dev/null (never the real one: a bug would replace it)
    argv = {"export-nir": ["export-nir", str(art), "-q"],
            "run": ["run", str(art), "-i", str(x), "-q"]}[command]
    before = listing(tmp_path)
    folder = [] if command == "run" else [str(tmp_path / "dir")]  # run: writes dir.npz beside
    for path in (str(device or fifo), str(fifo), *folder, "x\0y.nir", "", "out/"):
        assert main([*argv, "-o", path]) == 1, path
        err = capsys.readouterr().err
        assert err.startswith("error: output ") and len(err.strip().splitlines()) == 1, err
    assert listing(tmp_path) == before and fifo.is_fifo()  # no null.npz, no null.report.json
    if device is not None:
        assert device.is_char_device()


def test_sweep_figure_names_must_be_plain_file_names(tmp_path):
    from radarsnn.sweep.figures import draw_figures
    from radarsnn.sweep.sections import FigureSpec
    from radarsnn.sweep.spec import parse_spec

    base = {"name": "s", "chains": {"c": "c.yaml"},
            "frames": {"source": "scene", "n_frames": 1, "frames_per_cell": 1}}
    for i, name in enumerate(["../../X", "/abs/Y", "a/b", ".hidden", "", "x" * 101]):
        figures = [{"kind": "fig7"}] * i + [{"kind": "pareto", "name": name}]
        with pytest.raises(CompileError, match=rf"field 'figures\.{i}\.name'.*not a path"):
            parse_spec({**base, "figures": figures})
    with pytest.raises(CompileError, match="figure files.*repeat"):
        parse_spec({**base, "figures": [{"kind": "fig7", "name": "pareto"}, "pareto"]})
    forged = FigureSpec.model_construct(kind="pareto", name="../../X")  # no validation
    rows = [{"point": "p", "params": {}, "complete": True, "error": None,
             "metrics": {"m": {"f1": 1.0}}, "cost": {"neurons": 1}}]
    with pytest.raises(CompileError, match="outside"):
        draw_figures([forged], rows, tmp_path / "figures")
    assert listing(tmp_path) == ["figures"]


def test_run_output_named_like_a_folder_goes_beside_it(files, tmp_path):
    art, x = files
    (tmp_path / "out").mkdir()
    assert main(["run", str(art), "-i", str(x), "-o", str(tmp_path / "out"), "-q"]) == 0
    assert listing(tmp_path) == ["out", "out.npz"]  # the .npz suffix names another path
