"""Nothing is lost on faults: saving replaces an artifact directory atomically, a full disk
leaves the previous files and no temporaries, and outputs are complete or absent.

Issue "Hostile input, round two", items 10-12: 60 SIGKILLs while saving a program over a
valid one left 2 directories broken (the old artifact lost) and 13 with a stray
``arrays.npz.tmp``; re-saving a program with fewer networks kept a stale ``networks/1``;
a full disk during ``radarsnn run -o`` left a truncated ``out.npz`` and an error that did
not name it, and elsewhere ``.tmp`` files.  Full disks are simulated by ``tests/faults.py``
(``disk_full``: every write below ``tmp_path`` fails with ENOSPC after a byte budget).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from faults import fault_chain, kill_while_saving, listing, tree_bytes

from backends import load, load_program, save, save_program
from backends.artifact import read_manifest
from backends.atomic import stale_temporaries, write_atomic
from backends.manifest import HASH_KEY
from backends.program_artifact import read_program_manifest
from compiler.compile import compile_graph
from ir.errors import ArtifactError
from radarsnn.cli import main

GRAPH, X = fault_chain("faults")


@pytest.fixture(scope="module")
def programs():
    """The chain with two spiking networks (window as a spiking motif) and with one."""
    two = compile_graph(GRAPH, target="loihi2", calibration_inputs=X, motifs={"w": "time"})
    one = compile_graph(GRAPH, target="loihi2", calibration_inputs=X)
    assert (len(two.networks), len(one.networks)) == (2, 1)
    return two, one


def _digest(folder: Path) -> str:
    return read_program_manifest(folder)[HASH_KEY]


def test_resaving_a_program_with_fewer_networks_leaves_no_stale_network(programs, tmp_path):
    two, one = programs
    folder = save_program(two, tmp_path / "art")
    assert sorted(p.name for p in (folder / "networks").iterdir()) == ["0", "1"]
    save_program(one, folder)
    assert sorted(p.name for p in (folder / "networks").iterdir()) == ["0"]
    assert len(load_program(folder).networks) == 1
    assert os.listdir(tmp_path) == ["art"]


def test_saving_replaces_exactly_what_a_fresh_save_writes(programs, tmp_path):
    two, one = programs
    save_program(two, tmp_path / "over")
    (tmp_path / "over" / "arrays.npz.tmp").write_bytes(b"stray from an old radarsnn")
    save_program(one, tmp_path / "over")
    save_program(one, tmp_path / "fresh")
    assert tree_bytes(tmp_path / "over") == tree_bytes(tmp_path / "fresh")
    assert sorted(os.listdir(tmp_path)) == ["fresh", "over"]


def test_saving_over_foreign_files_or_the_working_directory_is_refused(programs, tmp_path,
                                                                      monkeypatch):
    _, one = programs
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep me")
    with pytest.raises(ArtifactError, match=r"mine.*notes\.txt.*empty or new directory"):
        save_program(one, tmp_path / "mine")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep me"
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")
    with pytest.raises(ArtifactError, match="current working directory"):
        save_program(one, ".")
    with pytest.raises(ArtifactError, match="not a directory"):
        save(one.networks[0], tmp_path / "mine" / "notes.txt")


@pytest.mark.parametrize("fraction", [0.0, 0.3, 0.95])
def test_a_full_disk_keeps_the_previous_program_and_leaves_no_temporaries(
        programs, tmp_path, disk_full, fraction):
    two, one = programs
    folder = save_program(one, tmp_path / "art")
    before = tree_bytes(folder)
    size = sum(len(b) for b in tree_bytes(save_program(two, tmp_path / "size")).values())
    with disk_full(free=int(fraction * size)) as budget, \
            pytest.raises(ArtifactError, match=r"art.*No space left on device"):
        save_program(two, folder)
    assert budget.failures >= 1
    assert tree_bytes(folder) == before and sorted(os.listdir(tmp_path)) == ["art", "size"]
    with disk_full(free=int(fraction * size)), pytest.raises(ArtifactError, match="new"):
        save_program(two, tmp_path / "new")  # a first save: nothing is left at all
    assert sorted(os.listdir(tmp_path)) == ["art", "size"]


def test_a_full_disk_keeps_the_previous_network_and_leaves_no_temporaries(
        programs, tmp_path, disk_full):
    two, one = programs
    folder = save(one.networks[0], tmp_path / "net")
    before = tree_bytes(folder)
    with disk_full(free=300), pytest.raises(ArtifactError, match="net.*No space left"):
        save(two.networks[0], folder)
    assert tree_bytes(folder) == before and os.listdir(tmp_path) == ["net"]
    write_atomic(tmp_path / "f.bin", b"old")
    with disk_full(free=2), pytest.raises(OSError, match="No space left"):
        write_atomic(tmp_path / "f.bin", b"new bytes")
    assert (tmp_path / "f.bin").read_bytes() == b"old"
    assert sorted(os.listdir(tmp_path)) == ["f.bin", "net"]


def test_a_full_disk_during_emit_leaves_no_temporaries(programs, tmp_path, disk_full):
    from backends.emit import emit_numpy

    with disk_full(free=5000), pytest.raises(ArtifactError, match="pkg.*No space left"):
        emit_numpy(programs[1], tmp_path / "pkg")
    assert not [p for p in listing(tmp_path) if p.endswith(".tmp")]


def test_run_output_on_a_full_disk_names_the_file_and_keeps_the_old_one(
        programs, tmp_path, disk_full, capsys):
    art = save_program(programs[1], tmp_path / "art")
    np.save(tmp_path / "x.npy", X["a"])
    out = tmp_path / "out.npz"
    argv = ["run", str(art), "-i", str(tmp_path / "x.npy"), "-o", str(out), "--quiet"]
    before = listing(tmp_path)
    with disk_full(free=100):
        assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1
    assert str(out) in err and "No space left on device" in err
    assert listing(tmp_path) == before  # no truncated out.npz, no temporary
    assert main(argv) == 0
    good = out.read_bytes()
    with disk_full(free=0):
        assert main(argv) == 1
    assert out.read_bytes() == good and listing(tmp_path) == sorted(before + ["out.npz"])
    assert np.load(out)["o"].shape == (8,)
    with disk_full(free=10):
        assert main(["schema", "-o", str(tmp_path / "schema.json")]) == 1
    assert "schema.json" in capsys.readouterr().err
    assert not (tmp_path / "schema.json").exists()


def test_without_an_atomic_exchange_the_old_tree_is_renamed_aside_then_removed(
        programs, tmp_path, monkeypatch):
    import backends.atomic as atomic

    two, one = programs
    save_program(two, tmp_path / "fresh")
    monkeypatch.setattr(atomic, "_exchange", lambda a, b: False)  # another OS or file system
    save_program(one, tmp_path / "art")
    save_program(two, tmp_path / "art")
    assert tree_bytes(tmp_path / "art") == tree_bytes(tmp_path / "fresh")
    assert sorted(os.listdir(tmp_path)) == ["art", "fresh"]


def test_stale_temporaries_of_dead_processes_are_removed_by_the_next_save(programs, tmp_path):
    _, one = programs
    dead = tmp_path / ".art.999999999-0123abcd.saving"
    old = tmp_path / ".art.999999998-0123abcd.old"
    live = tmp_path / f".art.{os.getppid()}-0123abcd.saving"  # a running process: kept
    for p in (dead, old, live):
        (p / "networks").mkdir(parents=True)
    assert stale_temporaries(tmp_path / "art") == [old, dead]
    save_program(one, tmp_path / "art")
    assert sorted(os.listdir(tmp_path)) == sorted(["art", live.name])
    (tmp_path / ".o.npz.999999999-0123abcd.tmp").write_bytes(b"half")
    write_atomic(tmp_path / "o.npz", b"x")
    assert sorted(os.listdir(tmp_path)) == sorted(["art", "o.npz", live.name])


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_sigkill_while_saving_a_program_leaves_the_old_or_the_new_one(programs, tmp_path):
    two, one = programs
    digests = {_digest(save_program(p, tmp_path / f"ref{i}")): f"v{i}"
               for i, p in enumerate((two, one))}

    def check(target: Path) -> str:
        program = load_program(target)  # complete and consistent, or this raises
        assert sorted(os.listdir(target / "networks")) == [
            str(i) for i in range(len(program.networks))]
        return digests[_digest(target)]

    seen = kill_while_saving(tmp_path, [two, one], save_program, check, kills=30, seed=10)
    assert set(seen) <= {"v0", "v1"}
    save_program(one, tmp_path / "target")  # the next save removes what the kills left
    assert sorted(os.listdir(tmp_path)) == ["ref0", "ref1", "target"]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_sigkill_while_saving_a_network_leaves_the_old_or_the_new_one(programs, tmp_path):
    nets = [programs[0].networks[0], programs[1].networks[0]]
    digests = {read_manifest(save(n, tmp_path / f"ref{i}"))[HASH_KEY]: f"v{i}"
               for i, n in enumerate(nets)}

    def check(target: Path) -> str:
        load(target)  # complete and consistent, or this raises
        return digests[read_manifest(target)[HASH_KEY]]

    seen = kill_while_saving(tmp_path, nets, save, check, kills=12, seed=11)
    assert set(seen) <= {"v0", "v1"}
    save(nets[0], tmp_path / "target")
    assert sorted(os.listdir(tmp_path)) == ["ref0", "ref1", "target"]
