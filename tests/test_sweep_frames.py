"""Frame sources of a sweep: seeded scene frames independent of slicing, folder files."""

from __future__ import annotations

import numpy as np
import pytest

from compiler.sweep.frames import folder_files, frame_rng, load_frames, random_scene
from compiler.sweep.spec import FolderFrames, SceneFrames
from ir.errors import RadarConfigError


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
    with pytest.raises(RadarConfigError, match=r"a.npy' is not a readable .npy array"):
        load_frames(src, tmp_path, 0, 1)
