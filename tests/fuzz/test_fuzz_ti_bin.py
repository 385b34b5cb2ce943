"""Fuzz: TI ``.bin`` layouts and captures — ``--bin-layout`` spellings (Unicode digits,
hostile strings, huge counts) and files of any size against any small layout.

``TiBinLayout.parse`` returns a layout or raises :class:`~ir.errors.RadarConfigError`;
``read_ti_bin`` returns whole frames — each frame equal to that frame's bytes read alone (no
``I0 I1 Q0 Q1`` pair across a frame boundary) — or raises ``RadarConfigError``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import HOSTILE_STRINGS, budget, outcome
from hypothesis import given, note
from hypothesis import strategies as st

from radar.ti_capture import TI_DEVICES, TiBinLayout, read_ti_bin

DIGITS = st.sampled_from(["1", "2", "4", "0", "²", "١", "𝟙", "٣", "-1", "+2", "1.0", "9" * 12,
                          "9" * 5000, "", " 2", "0x4", "1e3", *HOSTILE_STRINGS])
ITEMS = st.sampled_from(["samples", "chirps", "rx", "tx", "bits", "device", "complex", "real",
                         "x", ""])


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-ti-") as tmp:
        yield Path(tmp)


@budget(0.3)
@given(st.lists(st.tuples(ITEMS, DIGITS), max_size=6))
def test_layout_spellings(items) -> None:
    text = ",".join(f"{k}={v}" if k not in ("complex", "real") else k for k, v in items)
    note(repr(text))
    layout = outcome(lambda: TiBinLayout.parse(text), ["--bin-layout", text])
    if layout is not None:
        assert TiBinLayout.parse(layout.describe()) == layout


@budget(0.7)
@given(st.integers(1, 4), st.integers(1, 3), st.integers(1, 4), st.integers(1, 2),
       st.booleans(), st.sampled_from(sorted(TI_DEVICES)), st.integers(0, 80),
       st.integers(0, 9))
def test_captures_of_any_size(folder, samples, chirps, rx, tx, iq, device, words, slot) -> None:
    path = folder / f"cap{slot}.bin"
    np.arange(words, dtype="<i2").tofile(path)
    note(f"{samples=} {chirps=} {rx=} {tx=} {iq=} {device=} {words=}")

    def call():
        layout = TiBinLayout(n_samples=samples, n_chirps=chirps, n_rx=rx, n_tx=tx, complex=iq,
                             device=device)
        adc = read_ti_bin(path, layout)
        frames = words // layout.words_per_frame
        assert adc.shape == layout.shape(frames) and words % layout.words_per_frame == 0
        one = folder / f"one{slot}.bin"
        for f in range(frames):  # each frame decodes alone to the same values
            raw = np.arange(words, dtype="<i2")[f * layout.words_per_frame:
                                                (f + 1) * layout.words_per_frame]
            raw.tofile(one)
            np.testing.assert_array_equal(read_ti_bin(one, layout)[0], adc[f])

    outcome(call, [str(path), "samples", "rx", "n_rx", "xwr14xx", "frame"])
