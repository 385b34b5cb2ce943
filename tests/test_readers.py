"""Readers of files radar users have on disk: TI raw ADC ``.bin``, MATLAB ``.mat``, ``.npz``.

The ``.bin`` files are written here from a known cube by the word order TI documents
(SWRA581B §5 and §6), independently of the reader, and read back.
"""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from scipy.io import savemat

from ir.errors import RadarConfigError
from radar.readers import read_mat_array, read_npz_array
from radar.ti_capture import TI_AXES, TiBinLayout, read_ti_bin


def _cube(rng, frames, loops, tx, rx, n, complex_=True):
    """Integer ADC codes ``[frame, loop, tx, rx, sample]``."""
    shape = (frames, loops, tx, rx, n)
    cube = rng.integers(-2000, 2000, shape).astype(np.float64)
    if complex_:
        cube = cube + 1j * rng.integers(-2000, 2000, shape)
    return cube


def _words_xwr16xx(cube):
    """RX-major chirps; complex as I0 I1 Q0 Q1 groups."""
    flat = cube.reshape(-1)
    if not np.iscomplexobj(flat):
        return flat.astype("<i2")
    pairs = flat.reshape(-1, 2)
    return np.stack([pairs.real[:, 0], pairs.real[:, 1], pairs.imag[:, 0], pairs.imag[:, 1]],
                    axis=1).reshape(-1).astype("<i2")


def _words_xwr14xx(cube):
    """Per sample time the 4 lanes: I(rx0..3) then Q(rx0..3)."""
    by_time = cube.transpose(0, 1, 2, 4, 3).reshape(-1, cube.shape[3])  # [time, lane]
    if not np.iscomplexobj(by_time):
        return by_time.reshape(-1).astype("<i2")
    return np.concatenate([by_time.real, by_time.imag], axis=1).reshape(-1).astype("<i2")


def _expected(cube):
    f, loops, tx, rx, n = cube.shape
    return cube.transpose(0, 2, 3, 1, 4).reshape(f, tx * rx, loops, n)


@pytest.mark.parametrize("device, encode, rx", [("xwr16xx", _words_xwr16xx, 3),
                                                ("xwr14xx", _words_xwr14xx, 4)])
@pytest.mark.parametrize("complex_", [True, False])
def test_a_bin_written_in_the_documented_order_reads_back(tmp_path, device, encode, rx,
                                                          complex_):
    rng = np.random.default_rng(0)
    cube = _cube(rng, frames=3, loops=5, tx=2, rx=rx, n=6, complex_=complex_)
    encode(cube).tofile(tmp_path / "adc.bin")
    layout = TiBinLayout(n_samples=6, n_chirps=5, n_rx=rx, n_tx=2, complex=complex_,
                         device=device)
    adc = read_ti_bin(tmp_path / "adc.bin", layout)
    assert TI_AXES == ("frame", "rx", "chirp", "sample")
    assert adc.shape == (3, 2 * rx, 5, 6) == layout.shape(frames=3)
    assert adc.dtype == (np.complex128 if complex_ else np.float64)
    np.testing.assert_array_equal(adc, _expected(cube))
    # virtual channel tx * n_rx + rx, chirp = loop: TX 1's RX 0 in loop 2 of frame 1
    np.testing.assert_array_equal(adc[1, rx, 2], cube[1, 2, 1, 0])
    part = read_ti_bin(tmp_path / "adc.bin", layout, first_frame=1, n_frames=2)
    np.testing.assert_array_equal(part, _expected(cube)[1:])


def test_the_pairs_are_i0_i1_q0_q1_by_hand(tmp_path):
    np.array([1, 2, 10, 20, 3, 4, 30, 40], dtype="<i2").tofile(tmp_path / "a.bin")
    adc = read_ti_bin(tmp_path / "a.bin", TiBinLayout.parse("samples=2,chirps=1,rx=2"))
    assert adc[0, :, 0].tolist() == [[1 + 10j, 2 + 20j], [3 + 30j, 4 + 40j]]


def test_12_bit_codes_are_sign_extended(tmp_path):
    np.array([0x0FFF, 0x0800, 0x07FF, 1], dtype="<u2").tofile(tmp_path / "a.bin")
    layout = TiBinLayout.parse("samples=4,chirps=1,rx=1,real,bits=12")
    assert read_ti_bin(tmp_path / "a.bin", layout).ravel().tolist() == [-1, -2048, 2047, 1]


def test_the_layout_from_a_radar_config():
    from radar.config import preset

    layout = TiBinLayout.from_config(preset("carrada"))
    assert (layout.n_samples, layout.n_chirps, layout.n_rx, layout.n_tx, layout.complex) == (
        256, 64, 4, 2, True)


def test_a_size_that_is_not_whole_frames_names_the_file_size_and_frame(tmp_path):
    path = tmp_path / "capture.bin"
    np.zeros(1000, dtype="<i2").tofile(path)
    with pytest.raises(RadarConfigError) as info:
        read_ti_bin(path, TiBinLayout.parse("samples=256,chirps=128,rx=4"))
    message = str(info.value)
    for part in (str(path), "2000 bytes", "not a multiple", "524288 bytes", "samples",
                 "complex/real"):
        assert part in message


def test_empty_missing_and_out_of_range_frames(tmp_path):
    layout = TiBinLayout.parse("samples=2,chirps=1,rx=1,real")
    (tmp_path / "empty.bin").write_bytes(b"")
    with pytest.raises(RadarConfigError, match=r"empty\.bin is empty; expected frames of 4"):
        read_ti_bin(tmp_path / "empty.bin", layout)
    with pytest.raises(RadarConfigError, match=r"nope\.bin: cannot read it"):
        read_ti_bin(tmp_path / "nope.bin", layout)
    np.zeros(4, dtype="<i2").tofile(tmp_path / "two.bin")
    with pytest.raises(RadarConfigError, match=r"holds 2 frame\(s\).*from 1 are not all in it"):
        read_ti_bin(tmp_path / "two.bin", layout, first_frame=1, n_frames=2)
    with pytest.raises(RadarConfigError, match=r"over the limit of 10 bytes.*fewer frames"):
        read_ti_bin(tmp_path / "two.bin", layout, max_bytes=10)


@pytest.mark.parametrize("text, match", [
    ("samples=256,rx=4", r"lacks chirps="),
    ("samples=256,chirps=x,rx=4", r"chirps='x' is not a positive integer"),
    ("samples=256,chirps=2,rx=4,lanes=2", r"'lanes=2' is not one of the items"),
    ("samples=256,chirps=0,rx=4", r"n_chirps=0 must be a positive integer"),
    ("samples=256,chirps=2,rx=4,device=awr2944", r"device='awr2944' is not a TI device"),
    ("samples=256,chirps=2,rx=2,device=xwr14xx", r"always carries 4 LVDS lanes"),
    ("samples=256,chirps=2,rx=4,bits=10", r"adc_bits=10"),
])
def test_bad_layouts_are_refused(text, match):
    with pytest.raises(RadarConfigError, match=match):
        TiBinLayout.parse(text)


def test_mat_variables_by_name(tmp_path):
    path = tmp_path / "cube.mat"
    adc = np.arange(24.0).reshape(2, 3, 4) + 1j
    savemat(path, {"adc": adc, "chirp": np.arange(5, dtype=np.int16)})
    got = read_mat_array(path, "adc")
    assert got.dtype == np.complex128
    np.testing.assert_array_equal(got, adc)
    assert read_mat_array(path, "chirp").tolist() == [0, 1, 2, 3, 4]  # a vector is 1-D
    assert read_mat_array(path, "chirp", vector_1d=False).shape == (1, 5)
    with pytest.raises(RadarConfigError, match=r"cube\.mat holds 2 variables \('adc', 'chirp'\)"
                                               r"; name the one to read"):
        read_mat_array(path)
    with pytest.raises(RadarConfigError, match=r"has no variable 'x'; its variables are 'adc', "
                                               r"'chirp'"):
        read_mat_array(path, "x")


@pytest.mark.parametrize("value, cls", [({"a": 1.0}, "struct"),
                                        (np.array([1.0, "a"], dtype=object), "cell"),
                                        ("text", "char")])
def test_mat_structs_cells_and_strings_are_refused(tmp_path, value, cls):
    savemat(tmp_path / "s.mat", {"v": value})
    with pytest.raises(RadarConfigError, match=rf"variable 'v' is a MATLAB {cls}, not a numeric"):
        read_mat_array(tmp_path / "s.mat")


def test_a_damaged_or_missing_mat_file(tmp_path):
    (tmp_path / "bad.mat").write_bytes(b"not a mat file" * 20)
    with pytest.raises(RadarConfigError, match=r"bad\.mat: not a readable \.mat file.*-v7"):
        read_mat_array(tmp_path / "bad.mat")
    with pytest.raises(RadarConfigError, match=r"no such file"):
        read_mat_array(tmp_path / "none.mat")


def test_npz_arrays_by_key(tmp_path):
    path = tmp_path / "out.npz"
    np.savez(path, det=np.eye(2), rd=np.arange(3.0))
    assert read_npz_array(path, "rd").tolist() == [0.0, 1.0, 2.0]
    with pytest.raises(RadarConfigError, match=r"holds 2 arrays \('det', 'rd'\).*FILE\.npz:NAME"):
        read_npz_array(path)
    with pytest.raises(RadarConfigError, match=r"has no array 'x'; its arrays are 'det', 'rd'"):
        read_npz_array(path, "x")
    np.savez(tmp_path / "one.npz", only=np.ones(2))
    assert read_npz_array(tmp_path / "one.npz").tolist() == [1.0, 1.0]


def test_npz_object_arrays_forged_headers_and_non_zips_are_refused(tmp_path):
    np.savez(tmp_path / "obj.npz", o=np.array([{"a": 1}], dtype=object))
    with pytest.raises(RadarConfigError, match=r"object array, refused"):
        read_npz_array(tmp_path / "obj.npz")
    header = np.lib.format.header_data_from_array_1_0(np.zeros(2))
    header["shape"] = (10**12,)
    forged = tmp_path / "forged.npz"
    with zipfile.ZipFile(forged, "w") as zf, zf.open("x.npy", "w") as f:
        np.lib.format.write_array_header_1_0(f, header)
        f.write(np.zeros(2).tobytes())
    with pytest.raises(RadarConfigError, match=r"declares \(1000000000000,\).*over the limit"):
        read_npz_array(forged)
    with pytest.raises(RadarConfigError, match=r"but its member holds 16 bytes"):
        read_npz_array(forged, max_bytes=10**14)
    (tmp_path / "no.npz").write_bytes(b"hello")
    with pytest.raises(RadarConfigError, match=r"no\.npz: not a readable \.npz archive"):
        read_npz_array(tmp_path / "no.npz")
