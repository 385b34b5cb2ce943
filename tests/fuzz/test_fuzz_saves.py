"""Fuzz: saving under faults — a crash between any two file-system operations, or a full disk
at any byte, leaves the previous artifact or the new one, and no temporaries after a failure.

Starting states: no directory, an empty one, a network or a program artifact (with one or
two networks), with a stray ``arrays.npz.tmp`` of an older radarsnn.  What is saved: either
network, either program.

* **crash**: every file-system operation of :mod:`backends.atomic` (``mkdir``, each chunk
  written, ``rename``/``replace``, the directory exchange, removals) is preceded by a
  snapshot of the parent folder — exactly what a SIGKILL at that moment leaves.  Every
  snapshot's target must load as the old artifact (or be absent/empty as before) or as the
  new one: never a mixture, never a broken directory.  (``tests/test_artifact_faults.py``
  kills real processes.)
* **full disk**: a byte budget (and ``ENOSPC``, ``EDQUOT``, ``EFBIG`` or ``EIO``) for
  every write below the folder: the save raises an ``ArtifactError`` naming the folder,
  the old tree is byte for byte unchanged and nothing else is left; ``radarsnn run -o``
  under a full disk exits 2 and leaves the previous output (or none) and no temporary.
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from faults import DiskFull, fault_chain, tree_bytes
from fuzz_support import budget, expect_radarsnn_error
from hypothesis import given, note
from hypothesis import strategies as st

import backends.atomic as atomic
from backends import load, save_program
from backends.artifact import read_manifest
from backends.artifact import save as save_network
from backends.manifest import HASH_KEY
from backends.program_artifact import is_program, read_program_manifest
from compiler.compile import compile_graph
from compiler.program import CompiledProgram
from ir.errors import ArtifactError

GRAPH, X = fault_chain("fuzz-saves")
TWO = compile_graph(GRAPH, target="loihi2", calibration_inputs=X, motifs={"w": "time"})
ONE = compile_graph(GRAPH, target="loihi2", calibration_inputs=X)
OBJECTS = {"program-2": TWO, "program-1": ONE, "network-a": TWO.networks[0],
           "network-b": ONE.networks[0]}
STARTS = ["absent", "empty", *OBJECTS]


def _identity(folder: Path) -> str | None:
    """The digest of what ``folder`` holds, checked by a full load (None: absent or empty)."""
    if not folder.exists() or all(p.name.endswith(".tmp") for p in folder.iterdir()):
        return None
    load(folder)
    return (read_program_manifest if is_program(folder) else read_manifest)(folder)[HASH_KEY]


def _save(obj, target: Path) -> Path:
    """``save_program`` or ``artifact.save`` (``backends.save`` refuses networks over programs)."""
    return (save_program if isinstance(obj, CompiledProgram) else save_network)(obj, target)


def _start(root: Path, start: str, stray: bool) -> Path:
    target = root / "art"
    if start == "empty":
        target.mkdir()
    elif start != "absent":
        _save(OBJECTS[start], target)
    if stray and target.is_dir():
        (target / "arrays.npz.tmp").write_bytes(b"half an old write")
    return target


class _Snapshots:
    """Copy ``root`` before every file-system operation of a save (a crash at that moment)."""

    def __init__(self, root: Path, monkeypatch: pytest.MonkeyPatch) -> None:
        self.root, self.taken, self._busy = root, [], False
        self._where = Path(tempfile.mkdtemp(prefix="crash-", dir=root.parent))
        for owner, name in ((os, "mkdir"), (os, "rename"), (os, "replace"), (os, "unlink"),
                            (atomic, "_write"), (atomic, "_exchange"), (shutil, "rmtree")):
            monkeypatch.setattr(owner, name, self._wrap(getattr(owner, name)))

    def _wrap(self, real):
        def call(*args, **kwargs):
            if not self._busy:
                self._busy = True
                try:
                    copy = self._where / str(len(self.taken))
                    shutil.copytree(self.root, copy, symlinks=True)
                    self.taken.append(copy)
                finally:
                    self._busy = False
            return real(*args, **kwargs)
        return call


@budget(0.025)
@given(st.sampled_from(STARTS), st.booleans(), st.sampled_from(sorted(OBJECTS)))
def test_a_crash_at_any_step_leaves_the_old_or_the_new_artifact(tmp_path, start, stray,
                                                                 new) -> None:
    root = Path(tempfile.mkdtemp(dir=tmp_path))
    target = _start(root, start, stray)
    old = _identity(target)
    with pytest.MonkeyPatch.context() as mp:
        shots = _Snapshots(root, mp)
        _save(OBJECTS[new], target)
    final = _identity(target)
    note(f"{start} -> {new}: {len(shots.taken)} crash points")
    assert len(shots.taken) >= 3
    for shot in shots.taken:
        assert _identity(shot / "art") in (old, final), f"crash state {shot.name}"
    shutil.rmtree(shots._where)


@budget(0.03)
@given(st.sampled_from(STARTS), st.booleans(), st.sampled_from(sorted(OBJECTS)),
       st.floats(0.0, 1.0),
       st.sampled_from([errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO]))
def test_a_full_disk_at_any_byte_changes_nothing(tmp_path, start, stray, new, fraction,
                                                  code) -> None:
    root = Path(tempfile.mkdtemp(dir=tmp_path))
    target = _start(root, start, stray)
    before, names = (tree_bytes(target) if target.exists() else None), sorted(os.listdir(root))
    size = sum(len(b) for b in tree_bytes(_save(OBJECTS[new], root / "size")).values())
    shutil.rmtree(root / "size")
    with pytest.MonkeyPatch.context() as mp, DiskFull(mp, root)(int(fraction * size),
                                                                 code) as disk:
        try:
            _save(OBJECTS[new], target)
        except ArtifactError as err:
            expect_radarsnn_error(err, [str(target)])
            assert os.strerror(code) in str(err)
        else:
            assert disk.failures == 0  # everything fitted
            return
    assert sorted(os.listdir(root)) == names
    assert (tree_bytes(target) if target.exists() else None) == before


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    root = tmp_path_factory.mktemp("run")
    np.save(root / "x.npy", X["a"])
    return save_program(ONE, root / "art"), root / "x.npy"


@budget(0.02)
@given(st.floats(0.0, 1.0), st.sampled_from([errno.ENOSPC, errno.EDQUOT, errno.EIO]),
       st.booleans(), st.sampled_from(["out.npz", "out", "sub/out.npz"]))
def test_run_outputs_on_a_full_disk_are_complete_or_absent(tmp_path, run_files, fraction, code,
                                                           previous, name) -> None:
    from radarsnn.cli import main

    art, x = run_files
    root = Path(tempfile.mkdtemp(dir=tmp_path))
    (root / "sub").mkdir()
    out = root / name
    argv = ["run", str(art), "-i", str(x), "-o", str(out), "--quiet"]
    final = out if name.endswith(".npz") else out.with_name(out.name + ".npz")
    if previous:
        final.write_bytes(b"the previous output")
    before = tree_bytes(root)
    with pytest.MonkeyPatch.context() as mp, DiskFull(mp, root)(int(fraction * 600), code):
        status = main(argv)
    if status == 0:  # it fitted: the whole output
        assert np.load(final)["o"].shape == (8,)
        return
    assert status == 1
    assert tree_bytes(root) == before  # nothing truncated, no temporary
