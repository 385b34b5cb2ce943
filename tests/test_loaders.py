"""Loaders of the real captures: shapes, dtypes, the stored FFT, the OpenRadar layout, bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ir.errors import RadarConfigError
from radar.loaders import default_data_dir, load_openradar, load_ti_chirps


def test_ti_chirps_shape_dtype_and_stored_fft(shared_data):
    chirps, reference = load_ti_chirps(shared_data)
    assert chirps.shape == (4, 1024) and chirps.dtype == np.float64
    assert reference.shape == (4, 1024) and reference.dtype == np.complex128
    assert chirps.min() == -73.0 and chirps.max() == 69.0  # ADC codes, as the README says
    np.testing.assert_allclose(np.fft.fft(chirps, axis=1), reference, rtol=1e-5,
                               atol=1e-5 * np.abs(reference).max())
    # README: chirp 2 holds two close targets at range bins 42 and 66
    strongest = np.argsort(np.abs(reference[2, 1:512]))[::-1][:2] + 1
    assert sorted(strongest.tolist()) == [42, 66]


def test_openradar_frame_layout_and_strongest_reflection(shared_data):
    frame = load_openradar("simple_frame_1", shared_data)
    assert frame.shape == (128, 128) and frame.dtype == np.complex128
    parts = np.stack([frame.real, frame.imag])
    np.testing.assert_array_equal(parts, np.rint(parts))
    assert parts.min() >= -32768 and parts.max() <= 32767 and parts.min() < 0
    # rows are chirps, columns samples: remove each chirp's mean, range FFT along samples,
    # Doppler FFT along chirps; the strongest cell beyond leakage bins 0..3 is (zero, 107)
    centred = frame - frame.mean(axis=1, keepdims=True)
    rd = np.abs(np.fft.fftshift(np.fft.fft(np.fft.fft(centred, axis=1), axis=0), axes=0))
    rd[:, :4] = 0.0
    doppler, rng = np.unravel_index(np.argmax(rd), rd.shape)
    assert (int(doppler), int(rng)) == (64, 107)
    # the transposed reading does not give that answer, so the layout is chirp x sample
    rd_t = np.abs(np.fft.fftshift(np.fft.fft(np.fft.fft(centred.T, axis=1), axis=0), axes=0))
    rd_t[:, :4] = 0.0
    assert np.unravel_index(np.argmax(rd_t), rd_t.shape) != (64, 107)


def test_openradar_doppler_example(shared_data):
    frame = load_openradar("doppler_example", shared_data)
    assert frame.shape == (128, 256) and frame.dtype == np.complex128


def test_uint16_decoding_by_hand(tmp_path):
    (tmp_path / "openradar").mkdir()
    raw = np.zeros((128, 128), dtype=np.complex128)
    raw[0, :4] = [0 + 65535j, 32767 + 32768j, 32768 + 1j, 65535 + 0j]
    np.save(tmp_path / "openradar" / "simple_frame_1.npy", raw)
    frame = load_openradar(directory=tmp_path)
    np.testing.assert_array_equal(frame[0, :4], [0 - 1j, 32767 - 32768j, -32768 + 1j, -1 + 0j])


def test_default_data_dir_follows_env(monkeypatch, tmp_path):
    monkeypatch.setenv("RADARSNN_DATA", str(tmp_path))
    assert default_data_dir() == tmp_path
    monkeypatch.delenv("RADARSNN_DATA")
    assert default_data_dir() == Path(__file__).resolve().parents[1] / "radar" / "data"
    assert (default_data_dir() / "ti_chirps" / "LICENSE").is_file()
    assert (default_data_dir() / "openradar" / "LICENSE").is_file()


def _ti_folder(root: Path, chirps: np.ndarray | None = None) -> Path:
    folder = root / "ti_chirps"
    folder.mkdir()
    x = np.ones((4, 1024), dtype=np.float32) if chirps is None else chirps
    np.save(folder / "data_tum.npy", x)
    np.save(folder / "fft_result.npy", np.zeros((4, 1024), dtype=np.complex64))
    return folder


def test_missing_directory_says_how_to_point_at_data(tmp_path):
    with pytest.raises(RadarConfigError, match=r"ti_chirps does not exist.*RADARSNN_DATA"):
        load_ti_chirps(tmp_path / "nowhere")
    with pytest.raises(RadarConfigError, match=r"openradar does not exist.*RADARSNN_DATA"):
        load_openradar(directory=tmp_path)


def test_missing_file(tmp_path):
    folder = _ti_folder(tmp_path)
    (folder / "fft_result.npy").unlink()
    with pytest.raises(RadarConfigError, match=r"fft_result\.npy is missing.*complex.*4, 1024"):
        load_ti_chirps(tmp_path)


def test_truncated_file(tmp_path):
    folder = _ti_folder(tmp_path)
    path = folder / "data_tum.npy"
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(RadarConfigError, match=r"data_tum\.npy cannot be read.*truncated"):
        load_ti_chirps(tmp_path)


def test_not_an_npy_file(tmp_path):
    folder = _ti_folder(tmp_path)
    (folder / "data_tum.npy").write_text("import os; os.system('echo pwned')\n")
    with pytest.raises(RadarConfigError, match=r"data_tum\.npy cannot be read"):
        load_ti_chirps(tmp_path)


def test_pickled_object_array_is_refused(tmp_path):
    folder = _ti_folder(tmp_path)
    objects = np.empty((4, 1024), dtype=object)
    np.save(folder / "data_tum.npy", objects, allow_pickle=True)
    with pytest.raises(RadarConfigError, match=r"data_tum\.npy cannot be read"):
        load_ti_chirps(tmp_path)


def test_wrong_shape_and_dtype(tmp_path):
    _ti_folder(tmp_path, np.ones((4, 512), dtype=np.float32))
    with pytest.raises(RadarConfigError, match=r"data_tum\.npy has shape \(4, 512\), expected "
                                               r"\(4, 1024\)"):
        load_ti_chirps(tmp_path)
    other = tmp_path / "other"
    other.mkdir()
    _ti_folder(other, np.ones((4, 1024), dtype=np.int16))
    with pytest.raises(RadarConfigError, match=r"data_tum\.npy holds dtype int16, expected float"):
        load_ti_chirps(other)


@pytest.mark.parametrize("bad", [-1.0, 65536.0, 12.5])
def test_openradar_values_must_be_uint16_codes(tmp_path, bad):
    (tmp_path / "openradar").mkdir()
    raw = np.zeros((128, 256), dtype=np.complex128)
    raw[5, 7] = complex(0.0, bad)
    np.save(tmp_path / "openradar" / "doppler_example.npy", raw)
    with pytest.raises(RadarConfigError, match=r"1 values that are not unsigned 16-bit codes"):
        load_openradar("doppler_example", tmp_path)


def test_openradar_wrong_dtype_and_unknown_name(tmp_path):
    (tmp_path / "openradar").mkdir()
    np.save(tmp_path / "openradar" / "simple_frame_1.npy", np.zeros((128, 128)))
    with pytest.raises(RadarConfigError, match=r"holds dtype float64, expected complex"):
        load_openradar(directory=tmp_path)
    with pytest.raises(RadarConfigError, match=r"unknown OpenRadar capture 'frame_2'.*"
                                               r"doppler_example, simple_frame_1"):
        load_openradar("frame_2", tmp_path)
