"""Readers cost what the file holds and the port can take, not what a cap or a header allows.

Each memory claim is checked in a child interpreter under an address-space cap
(:func:`capped.run_capped`): a reader that reserves or decodes more than its bound fails
there with ``MemoryError`` instead of exhausting the machine.
"""

from __future__ import annotations

import json

import numpy as np
from capped import run_capped

_MIB = 1 << 20


def test_a_small_artifact_loads_under_a_small_address_space(tmp_path):
    # read_bytes(limit=4 GiB) used to call f.read(4 GiB + 1), which reserves 4 GiB first
    done = run_capped(f"""
        from pathlib import Path
        from backends.artifact_io import MAX_ARRAYS_BYTES, read_bytes
        (Path({str(tmp_path)!r}) / "f.bin").write_bytes(b"x" * 1000)
        """, f"""
        from pathlib import Path
        data = read_bytes(Path({str(tmp_path)!r}) / "f.bin", limit=MAX_ARRAYS_BYTES)
        print(len(data))
        """, headroom_bytes=512 * _MIB)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["1000"]


def test_read_bytes_reads_a_file_that_reports_no_size_and_one_that_grows(tmp_path):
    from pathlib import Path

    import pytest

    from backends.artifact_io import read_bytes
    from ir.errors import ArtifactError

    status = read_bytes(Path("/proc/self/status"), limit=1 << 20)  # st_size 0, holds text
    assert b"VmSize" in status
    with pytest.raises(ArtifactError, match=r"over the limit of 10 bytes"):
        read_bytes(Path("/proc/self/status"), limit=10)
    (tmp_path / "m.json").write_text(json.dumps({"a": 1}))
    assert read_bytes(tmp_path / "m.json", limit=1 << 30) == b'{"a": 1}'


def _outcome(setup: str, call: str, headroom_bytes: int = 512 * _MIB, timeout_s: float = 60.0):
    """``(kind, text)`` of ``call`` in a capped child: ``ok`` and the result's shape, or the
    exception's class name and message."""
    done = run_capped(setup, f"""
        import json
        try:
            result = {call}
            out = ["ok", str(getattr(result, "shape", result))]
        except BaseException as err:
            out = [type(err).__name__, str(err)[:300]]
        print(json.dumps(out))
        """, headroom_bytes=headroom_bytes, timeout_s=timeout_s)
    assert done.returncode == 0, done.stderr[-2000:]
    return tuple(json.loads(done.stdout.splitlines()[-1]))


def test_a_mat_variable_whose_data_element_inflates_past_its_shape_is_refused(tmp_path):
    from bombs import mat_bomb

    (tmp_path / "bomb.mat").write_bytes(mat_bomb(int(3.9 * (1 << 30))))  # 4 MB, 1x1 double
    (tmp_path / "dims.mat").write_bytes(mat_bomb(0, dims_bytes=3 << 30))  # the listing's bomb
    for name, why in [("bomb.mat", "inflates to more than 4112 bytes"),
                      ("dims.mat", "not a readable .mat file")]:
        # inflating took 31-47 s; the address-space cap is the check (the time it takes now:
        # benchmarks/hostile_inputs.py)
        kind, text = _outcome("from radar.readers import read_mat_array",
                              f"read_mat_array({str(tmp_path / name)!r})")
        assert kind == "RadarConfigError" and why in text, (kind, text)


def test_an_npz_bomb_is_refused_from_its_header_before_it_is_inflated(tmp_path):
    from bombs import npz_bomb

    # 4 MB declaring 3.9 GiB (within the 4 GiB cap) that the port (4,) cannot take
    (tmp_path / "bomb.npz").write_bytes(npz_bomb((int(3.9 * (1 << 30)) // 8,)))
    # decoding took 7-47 s; the address-space cap is the check (benchmarks/hostile_inputs.py
    # times it)
    kind, text = _outcome(
        "from radarsnn.cli.arrays import load_arrays",
        f"load_arrays([{str(tmp_path / 'bomb.npz')!r}], ['x'], 'chain c', shapes={{'x': (4,)}})")
    assert kind == "RadarConfigError", (kind, text)
    assert "declares shape (523449139,), but the port takes (4,)" in text


def test_a_bin_capture_is_checked_against_the_port_before_it_is_read(tmp_path):
    # sparse 512 MiB: decoding it would take 2 GiB; the port takes 64 chirps, not 128
    capture = tmp_path / "big.bin"
    with capture.open("wb") as f:
        f.truncate(512 * _MIB)
    # decoding took 7-47 s; the address-space cap is the check (benchmarks/hostile_inputs.py
    # times it)
    kind, text = _outcome(  # the reader's lazy imports (scipy) come before the cap
        "from radarsnn.cli.arrays import load_arrays\nimport radar.ti_capture",
        f"load_arrays([{str(capture)!r}], ['adc'], 'chain c', "
        "bin_layout='samples=256,chirps=128,rx=4', shapes={'adc': (4, 64, 256)})",
        headroom_bytes=256 * _MIB)
    assert kind == "RadarConfigError", (kind, text)
    assert "declares shape (1024, 4, 128, 256), but the port takes (4, 64, 256)" in text


def test_bin_decoding_needs_the_result_plus_bounded_pieces(tmp_path):
    # 96 MiB of words decode to 384 MiB of complex128; it used to peak at 3.3x that
    capture = tmp_path / "cap.bin"
    words = np.zeros(96 * _MIB // 2, dtype="<i2")
    words[:8] = [1, 2, 10, 20, 3, 4, 30, 40]
    words.tofile(capture)
    del words
    kind, text = _outcome(
        "from radar.ti_capture import TiBinLayout, read_ti_bin",
        f"read_ti_bin({str(capture)!r}, TiBinLayout.parse('samples=256,chirps=128,rx=4'))"
        "[0, 0, 0, :4].tolist()", headroom_bytes=(384 + 128) * _MIB)
    assert kind == "ok", (kind, text)
    assert text == str([1 + 10j, 2 + 20j, 3 + 30j, 4 + 40j])


def test_no_reader_waits_on_a_fifo(tmp_path):
    import os

    calls = {"f.npy": "read_npy_array({p!r})", "f.npz": "read_npz_array({p!r})",
             "f.mat": "read_mat_array({p!r})",
             "f.bin": "read_ti_bin({p!r}, TiBinLayout(2, 1, 1))"}
    body = ["import json", "out = []"]
    for name, call in calls.items():
        os.mkfifo(tmp_path / name)
        body += ["try:", f"    {call.format(p=str(tmp_path / name))}", "    out.append('read')",
                 "except RadarConfigError as err:", "    out.append(str(err))"]
    done = run_capped("from radar.readers import *\nfrom radar.ti_capture import *\n"
                      "from ir.errors import RadarConfigError",
                      "\n".join([*body, "print(json.dumps(out))"]), timeout_s=20)
    assert done.returncode == 0, done.stderr[-2000:]
    for name, text in zip(calls, json.loads(done.stdout), strict=True):
        assert "not a regular file" in text, (name, text)


def test_classifier_weights_are_read_by_the_bounded_npz_reader(tmp_path):
    import zipfile

    import pytest
    from bombs import npy_header

    from ir.classifier_forward.weights import load_weights
    from ir.errors import IRError
    from ir.ops.classify import Classifier

    # a member declaring 10**12 values: numpy's np.load raised _ArrayMemoryError
    with zipfile.ZipFile(tmp_path / "w.npz", "w") as zf:
        zf.writestr("conv.npy", npy_header((10**12,)) + bytes(16))
    op = Classifier.model_construct(weights=str(tmp_path / "w.npz"))
    with pytest.raises(IRError, match=r"cannot read weights .*w\.npz.*declares \(1000000000000,"
                                      r"\) float64 \(8000000000000 bytes\), over the limit"):
        load_weights(op, (16, 16), "cls")
