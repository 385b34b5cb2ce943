"""Conventional DSP (radar.dsp, .windows, .spectra): hand-worked values, matrix/FFT, captures."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ir.errors import RadarConfigError
from radar.dsp import MAGNITUDE_KINDS, dft, dft_bins, dft_matrix, magnitude, to_db
from radar.spectra import angle_fft, range_doppler_map
from radar.windows import WINDOW_KINDS, apply_window, window_coefficients

# ---------------------------------------------------------------- windows


def test_window_hand_values():
    assert window_coefficients("hann", 5).tolist() == [0.0, 0.5, 1.0, 0.5, 0.0]
    np.testing.assert_allclose(window_coefficients("hamming", 3), [0.08, 1.0, 0.08], atol=1e-15)
    np.testing.assert_allclose(window_coefficients("blackman", 3), [0.0, 1.0, 0.0], atol=1e-15)
    assert window_coefficients("rect", 4).tolist() == [1.0] * 4
    assert window_coefficients("hann", 1).tolist() == [1.0]


@given(n=st.integers(1, 300))
def test_windows_are_numpy_symmetric_windows(n):
    reference = {"hann": np.hanning, "hamming": np.hamming, "blackman": np.blackman}
    for kind, fn in reference.items():
        w = window_coefficients(kind, n)
        assert w.dtype == np.float64 and w.shape == (n,)
        np.testing.assert_allclose(w, fn(n), atol=1e-14)
        np.testing.assert_allclose(w, w[::-1], atol=1e-15)


def test_apply_window_along_axis():
    x = np.ones((5, 3), dtype=np.complex64)
    y = apply_window(x, "hann", axis=0)
    assert y.dtype == np.complex128
    np.testing.assert_array_equal(y[:, 1].real, [0.0, 0.5, 1.0, 0.5, 0.0])
    np.testing.assert_array_equal(apply_window(x, "hann", axis=-2), y)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: window_coefficients("hanning", 4), r"window kind='hanning'.*'hann', 'hamming'"),
        (lambda: window_coefficients("hann", 0), r"window length n=0"),
        (lambda: apply_window(np.ones((2, 2)), "hann", axis=2), r"axis=2 .* -2\.\.1"),
    ],
)
def test_window_errors(call, match):
    with pytest.raises(RadarConfigError, match=match):
        call()


# ---------------------------------------------------------------- DFT


def test_dft_matrix_hand_values():
    w = dft_matrix(4)
    expected = [[1, 1, 1, 1], [1, -1j, -1, 1j], [1, -1, 1, -1], [1, 1j, -1, -1j]]
    np.testing.assert_allclose(w, expected, atol=1e-15)
    np.testing.assert_allclose(
        dft_matrix(4, shift=True), np.asarray(expected)[[2, 3, 0, 1]], atol=1e-15
    )
    # zero-padded to 8, positive half: bin k row is exp(-2j pi k l / 8)
    w8 = dft_matrix(2, n_fft=8, keep="positive")
    r = np.sqrt(0.5)
    np.testing.assert_allclose(
        w8, [[1, 1], [1, r - 1j * r], [1, -1j], [1, -r - 1j * r]], atol=1e-15
    )


def test_dft_bins_conventions():
    assert dft_bins(5, shift=True).tolist() == [3, 4, 0, 1, 2]  # zero at index 5 // 2
    assert dft_bins(6, shift=True).tolist() == [3, 4, 5, 0, 1, 2]
    assert dft_bins(7, keep="positive").tolist() == [0, 1, 2]


def test_dft_hand_values():
    np.testing.assert_allclose(dft([0.0, 1.0, 0.0, 0.0]), [1, -1j, -1, 1j], atol=1e-15)
    np.testing.assert_allclose(dft([1.0, 1.0, 1.0, 1.0], shift=True), [0, 0, 4, 0], atol=1e-15)
    assert dft(np.ones(3, np.float32)).dtype == np.complex128


@given(
    n_in=st.integers(1, 40),
    pad=st.integers(0, 20),
    keep=st.sampled_from(["all", "positive"]),
    shift=st.booleans(),
    is_complex=st.booleans(),
    axis=st.integers(-3, 2),
    seed=st.integers(0, 2**32 - 1),
)
def test_dft_equals_matrix(n_in, pad, keep, shift, is_complex, axis, seed):
    n_fft = n_in + pad
    if keep == "positive" and n_fft < 2:
        n_fft = 2
    rng = np.random.default_rng(seed)
    shape = [3, 2, 4]
    shape[axis] = n_in
    x = rng.standard_normal(shape)
    if is_complex:
        x = x + 1j * rng.standard_normal(shape)
    got = dft(x, axis, n_fft=n_fft, keep=keep, shift=shift)
    w = dft_matrix(n_in, n_fft=n_fft, keep=keep, shift=shift)
    want = np.moveaxis(np.tensordot(w, x, axes=([1], [axis])), 0, axis)
    assert got.shape == want.shape and got.dtype == np.complex128
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))


def test_range_fft_of_real_ti_chirps(shared_data):
    """The conventional range FFT of the TI chirps equals the stored reference."""
    chirps = np.load(shared_data / "ti_chirps" / "data_tum.npy", allow_pickle=False)
    reference = np.load(shared_data / "ti_chirps" / "fft_result.npy", allow_pickle=False)
    got = dft(chirps, axis=1)
    assert got.shape == reference.shape == (4, 1024)
    np.testing.assert_allclose(got, reference, rtol=1e-5, atol=0)
    # the README's annotation of chirp 2: two close targets at range bins 42 and 66
    strongest = np.argsort(np.abs(got[2, 1:512]))[::-1][:2] + 1
    assert sorted(strongest.tolist()) == [42, 66]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: dft_matrix(8, n_fft=4), r"n_fft=4 is smaller than the input length 8"),
        (lambda: dft(np.ones(8), n_fft=4), r"n_fft=4 is smaller than the input length 8"),
        (lambda: dft(np.ones(4), keep="half"), r"keep='half'.*'all', 'positive'"),
        (lambda: dft_bins(1, keep="positive"), r"keeps no bins"),
        (lambda: dft(np.ones(4), axis=1), r"axis=1 is out of range"),
        (lambda: dft_matrix(0), r"n_in=0"),
    ],
)
def test_dft_errors(call, match):
    with pytest.raises(RadarConfigError, match=match):
        call()


# ---------------------------------------------------------------- magnitude and dB


def test_magnitude_hand_values():
    z = np.array([3 - 4j, -1 + 0j, 0j])
    assert magnitude(z).tolist() == [5.0, 1.0, 0.0]
    assert magnitude(z, "l1").tolist() == [7.0, 1.0, 0.0]
    assert magnitude(z, "square").tolist() == [25.0, 1.0, 0.0]
    assert set(MAGNITUDE_KINDS) == {"l2", "l1", "square"}
    with pytest.raises(RadarConfigError, match=r"magnitude kind='abs'.*'l2', 'l1', 'square'"):
        magnitude(z, "abs")


def test_to_db_hand_values():
    assert to_db([10.0, 0.1, 1.0, 0.0]).tolist() == [20.0, -20.0, 0.0, -300.0]
    assert to_db([3 + 4j]).tolist() == pytest.approx([20 * np.log10(5.0)])
    assert to_db([100.0, 0.0], domain="power", floor_db=-60.0).tolist() == [20.0, -60.0]
    assert to_db([1e-20], floor_db=-100.0).tolist() == [-100.0]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"x": [1.0], "domain": "volts"}, r"domain='volts'.*'amplitude', 'power'"),
        ({"x": [-1.0], "domain": "power"}, r"negative values \(min -1\)"),
        ({"x": [1j], "domain": "power"}, r"complex"),
        ({"x": [1.0], "floor_db": -np.inf}, r"floor_db=-inf"),
    ],
)
def test_to_db_errors(kwargs, match):
    x = kwargs.pop("x")
    with pytest.raises(RadarConfigError, match=match):
        to_db(x, **kwargs)


# ---------------------------------------------------------------- range-Doppler map


def _target_cube(n_rx, n_chirps, n_samples, range_bin, doppler_bin):
    m = np.arange(n_chirps)[:, None]
    l = np.arange(n_samples)[None, :]
    phase = 2 * np.pi * (range_bin * l / n_samples + doppler_bin * m / n_chirps)
    rx_phase = np.exp(1j * np.arange(n_rx) * 0.7)[:, None, None]
    return rx_phase * np.exp(1j * phase)[None]


@given(
    range_bin=st.integers(0, 15),
    doppler_bin=st.integers(-4, 3),
    n_rx=st.integers(1, 3),
)
def test_rd_map_puts_a_tone_in_its_bin(range_bin, doppler_bin, n_rx):
    cube = _target_cube(n_rx, 8, 16, range_bin, doppler_bin)
    rd = range_doppler_map(cube, window="rect")
    assert rd.shape == (16, 8)
    peak = np.unravel_index(np.argmax(rd), rd.shape)
    assert peak == (range_bin, doppler_bin + 4)  # zero Doppler at index 8 // 2
    assert rd[peak] == pytest.approx(n_rx * 8 * 16, rel=1e-12)
    rest = rd.copy()
    rest[peak] = 0.0
    assert rest.max() < 1e-9


@given(
    window=st.sampled_from(WINDOW_KINDS),
    keep=st.sampled_from(["all", "positive"]),
    shift=st.booleans(),
    mag=st.sampled_from(MAGNITUDE_KINDS),
    seed=st.integers(0, 2**32 - 1),
)
def test_rd_map_equals_explicit_matrix_chain(window, keep, shift, mag, seed):
    rng = np.random.default_rng(seed)
    cube = rng.standard_normal((2, 6, 10))  # real-sampled [rx, chirp, sample]
    w_range = dft_matrix(10, keep=keep) * window_coefficients(window, 10)[None, :]
    w_doppler = dft_matrix(6, shift=shift)
    spectrum = np.einsum("rl,xml,vm->xrv", w_range, cube, w_doppler)
    want = magnitude(spectrum, mag).sum(axis=0)
    got = range_doppler_map(cube, window=window, keep=keep, shift=shift, magnitude=mag)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * want.max())


def test_rd_map_axes_and_receivers():
    rng = np.random.default_rng(7)
    cube = rng.standard_normal((3, 4, 8)) + 1j * rng.standard_normal((3, 4, 8))
    per_rx = range_doppler_map(cube, sum_rx=False)
    assert per_rx.shape == (3, 8, 4)
    np.testing.assert_allclose(range_doppler_map(cube), per_rx.sum(axis=0), rtol=1e-14)
    permuted = np.transpose(cube, (2, 0, 1))  # [sample, rx, chirp]
    got = range_doppler_map(permuted, rx_axis=1, chirp_axis=2, sample_axis=0)
    np.testing.assert_allclose(got, range_doppler_map(cube), rtol=1e-13)
    np.testing.assert_allclose(range_doppler_map(cube[0], rx_axis=None), per_rx[0], rtol=1e-14)


def test_rd_map_of_real_openradar_frame(shared_data):
    """The README's fact: strongest non-leakage reflection at range bin 107, zero Doppler."""
    raw = np.load(shared_data / "openradar" / "simple_frame_1.npy", allow_pickle=False)

    def signed(v):
        return v - 65536.0 * (v >= 32768)

    frame = signed(raw.real) + 1j * signed(raw.imag)  # [chirp, sample]
    frame = frame - frame.mean(axis=1, keepdims=True)
    rd = range_doppler_map(frame, rx_axis=None)
    assert rd.shape == (128, 128)
    rd[:4] = 0.0  # leakage bins
    assert np.unravel_index(np.argmax(rd), rd.shape) == (107, 64)


@pytest.mark.parametrize(
    ("shape", "kwargs", "match"),
    [
        ((2, 3), {}, r"adc has 2 dimension\(s\).*rx_axis=None"),
        ((2, 3, 4), {"rx_axis": None}, r"adc has 3 dimension\(s\) but rx_axis=None"),
        ((2, 3, 4), {"rx_axis": 1}, r"must be three different axes"),
        ((2, 3, 4), {"sample_axis": 3}, r"sample_axis=3 is out of range"),
        ((2, 3, 4), {"window": "kaiser"}, r"window kind='kaiser'"),
    ],
)
def test_rd_map_errors(shape, kwargs, match):
    with pytest.raises(RadarConfigError, match=match):
        range_doppler_map(np.ones(shape), **kwargs)


def test_angle_fft_steering_vector():
    u = 3 / 16  # spatial frequency in cycles per element
    snapshot = np.exp(2j * np.pi * u * np.arange(8))
    spectrum = np.abs(angle_fft(snapshot, n_fft=16))
    assert int(np.argmax(spectrum)) == 16 // 2 + 3
    assert spectrum.max() == pytest.approx(8.0, rel=1e-12)
    batch = np.stack([snapshot, snapshot])
    np.testing.assert_allclose(
        angle_fft(batch.T, axis=0, n_fft=16)[:, 1], angle_fft(snapshot, n_fft=16)
    )
