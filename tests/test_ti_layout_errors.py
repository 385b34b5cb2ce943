"""TI ``.bin`` layouts that cannot hold whole frames, and ``--bin-layout`` spellings that are
not ASCII integers, are typed errors (never a ``ValueError`` traceback, never samples paired
across a frame boundary)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ir.errors import RadarConfigError
from radar.ti_capture import TiBinLayout, read_ti_bin
from radarsnn.cli.arrays import load_arrays


@pytest.mark.parametrize("words", [2, 4])  # one sample (4 bytes); "two frames" (8 bytes)
def test_an_odd_xwr16xx_complex_frame_is_refused(tmp_path, words):
    path = tmp_path / "one.bin"
    np.arange(words, dtype="<i2").tofile(path)
    with pytest.raises(RadarConfigError, match=r"xwr16xx complex .* pairs .* 1 complex samples"):
        read_ti_bin(path, TiBinLayout(n_samples=1, n_chirps=1, n_rx=1))


def test_even_frames_pair_within_each_frame(tmp_path):
    path = tmp_path / "two.bin"
    np.array([1, 2, 10, 20, 3, 4, 30, 40], dtype="<i2").tofile(path)  # two frames of 2
    adc = read_ti_bin(path, TiBinLayout(n_samples=2, n_chirps=1, n_rx=1))
    assert adc[:, 0, 0].tolist() == [[1 + 10j, 2 + 20j], [3 + 30j, 4 + 40j]]
    # odd counts stay legal where nothing pairs: real data, and the xwr14xx lanes
    assert TiBinLayout(n_samples=1, n_chirps=1, n_rx=1, complex=False).words_per_frame == 1
    assert TiBinLayout(n_samples=1, n_chirps=1, n_rx=4, device="xwr14xx").words_per_frame == 8


@pytest.mark.parametrize("value", ["²", "١٢", "𝟙", "1²", "-1", "+1", "1.0", "9" * 5000, ""])
def test_a_count_must_be_ascii_digits(value):
    with pytest.raises(RadarConfigError, match=r"is not a positive integer \(ASCII digits"):
        TiBinLayout.parse(f"samples={value},chirps=1,rx=1")


def test_the_cli_reader_raises_the_typed_error(tmp_path):
    np.zeros(4, "<i2").tofile(tmp_path / "c.bin")
    with pytest.raises(RadarConfigError, match=r"samples='²' is not a positive integer"):
        load_arrays([str(tmp_path / "c.bin")], ["x"], "a", bin_layout="samples=²,chirps=1,rx=1")


@given(st.text(max_size=40))
def test_parse_raises_only_typed_errors(text):
    try:
        TiBinLayout.parse(text)
    except RadarConfigError:
        pass
