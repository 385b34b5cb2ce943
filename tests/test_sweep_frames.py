"""Frame sources of a sweep: seeded scene frames independent of slicing, folder files."""

from __future__ import annotations

import numpy as np
import pytest

from ir.errors import RadarConfigError
from radarsnn.sweep.frames import folder_files, frame_rng, load_frames, random_scene
from radarsnn.sweep.sections import FolderFrames, SceneFrames


def test_scene_frame_does_not_depend_on_its_slice_and_streams_differ():
    src = SceneFrames(preset="carrada", scene="random", product="rd_power", seed=11)
    a = load_frames(src, ".", 0, 3)
    b = load_frames(src, ".", 2, 3)
    np.testing.assert_array_equal(a.arrays[2], b.arrays[0])
    assert a.truth[2] == b.truth[0] and a.indices == (0, 1, 2)
    cal = load_frames(src, ".", 2, 3, calibration=True)
    assert not np.array_equal(cal.arrays[0], b.arrays[0])
    db = load_frames(src.model_copy(update={"product": "rd_db"}), ".", 2, 3)
    np.testing.assert_allclose(db.arrays[0], 10 * np.log10(b.arrays[0]), rtol=1e-12)
    assert a.arrays[0].shape == (256, 64) and np.all(a.arrays[0] > 0)


def test_scene_frame_targets_lie_in_the_map_and_adc_product():
    src = SceneFrames(preset="carrada", scene="carrada", product="adc", seed=2)
    (adc,) = load_frames(src, ".", 0, 1).arrays
    assert adc.ndim == 3 and np.iscomplexobj(adc)
    with pytest.raises(RadarConfigError, match=r"scene 'moon' is unknown"):
        load_frames(src.model_copy(update={"scene": "moon"}), ".", 0, 1)


def test_random_scene_is_a_function_of_the_generator():
    one, two = random_scene(frame_rng(4, 0, 9)), random_scene(frame_rng(4, 0, 9))
    assert one == two and 1 <= len(one.targets) <= 3
    assert all(3.0 <= t.range_m <= 45.0 for t in one.targets)


def test_folder_source_splits_scored_and_calibration_files(tmp_path):
    for i in range(5):
        np.save(tmp_path / f"f{i}.npy", np.full((2, 3), float(i)))
    np.save(tmp_path / "labels.npy", np.array([0, 1, 2, 1, 0]))
    src = FolderFrames(source="folder", path=".", calibration_frames=2, labels="labels.npy")
    scored, cal = folder_files(src, tmp_path)
    assert [f.name for f in scored] == ["f0.npy", "f1.npy", "f2.npy"]
    assert [f.name for f in cal] == ["f3.npy", "f4.npy"]
    batch = load_frames(src, tmp_path, 1, 3)
    assert [a[0, 0] for a in batch.arrays] == [1.0, 2.0] and batch.labels == [1, 2]
    assert load_frames(src, tmp_path, 0, 2, calibration=True).arrays[1][0, 0] == 4.0
    with pytest.raises(RadarConfigError, match=r"n_frames = 4 but folder .* has 3 files"):
        folder_files(src.model_copy(update={"n_frames": 4}), tmp_path)
    with pytest.raises(RadarConfigError, match=r"has 5 '\*.npy' files but calibration takes"):
        folder_files(src.model_copy(update={"calibration_frames": 6}), tmp_path)


def test_folder_files_never_unpickle(tmp_path):
    np.save(tmp_path / "a.npy", np.array([{"x": 1}], dtype=object), allow_pickle=True)
    np.save(tmp_path / "b.npy", np.zeros(2))
    src = FolderFrames(source="folder", path=".", calibration_frames=1)
    with pytest.raises(RadarConfigError, match=r"a\.npy': object arrays are refused"):
        load_frames(src, tmp_path, 0, 1)


def test_hostile_folder_sources_are_typed_errors(tmp_path):
    import os

    from bombs import npy_header
    from capped import run_capped

    for i in range(3):
        np.save(tmp_path / f"f{i}.npy", np.zeros(2))
    os.mkfifo(tmp_path / "f3.npy")  # a reader opening it would wait for a writer forever
    done = run_capped(
        "from radarsnn.sweep.frames import folder_files\n"
        "from radarsnn.sweep.sections import FolderFrames\nfrom ir.errors import RadarConfigError",
        f"""
        try:
            folder_files(FolderFrames(source="folder", path="."), {str(tmp_path)!r})
            print("listed")
        except RadarConfigError as err:
            print(err)
        """, timeout_s=30)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "f3.npy' matches '*.npy' but is not a regular file" in done.stdout
    os.remove(tmp_path / "f3.npy")
    (tmp_path / "f3.npy").write_bytes(npy_header((10**12,)) + bytes(16))  # declares 8 TB
    src = FolderFrames(source="folder", path=".", calibration_frames=1)
    with pytest.raises(RadarConfigError, match=r"f3\.npy': the header declares \(1000000000000,"
                                               r"\) float64 \(8000000000000 bytes\), over the "
                                               r"limit of 4294967296"):
        load_frames(src, tmp_path, 0, 1, calibration=True)
    np.save(tmp_path / "f3.npy", np.array(["a", "b", "c"]))
    with pytest.raises(RadarConfigError, match=r"labels 'f3\.npy' hold <U1 values"):
        load_frames(src.model_copy(update={"labels": "f3.npy"}), tmp_path, 0, 1)


@pytest.mark.parametrize(("pattern", "why"), [
    ("", "is empty"), ("/etc/*", "is absolute"), ("*" * 500, "500 characters, over 255"),
    ("a*" * 9, "has 9 wildcards, over 8"), ("../*.npy", r"climbs out of the folder \('\.\.'\)"),
    ("a/../../*", "climbs out"), ("**/*.npy", "is recursive"), ("x\0.npy", "NUL byte"),
    ("C:*.npy", "is absolute"), (".", "names no file"), ("./", "names no file")])
def test_folder_patterns_are_relative_bounded_globs(pattern, why):
    from ir.errors import CompileError
    from radarsnn.sweep.spec import parse_spec

    spec = {"name": "t", "chains": {"a": {"name": "c", "nodes": [
        {"id": "x", "op": "input", "shape": {"range": 2}}, {"id": "o", "op": "output",
                                                             "input": "x"}]}},
            "frames": {"source": "folder", "path": ".", "pattern": pattern}}
    with pytest.raises(CompileError, match=rf"field 'frames\.folder\.pattern': Value error, "
                                           rf"pattern .* {why}"):
        parse_spec(spec)
    assert FolderFrames(source="folder", path=".", pattern="run1/f_*.npy").pattern
