"""Readers cost what the file holds and the port can take, not what a cap or a header allows.

Each memory claim is checked in a child interpreter under an address-space cap
(:func:`capped.run_capped`): a reader that reserves or decodes more than its bound fails
there with ``MemoryError`` instead of exhausting the machine.
"""

from __future__ import annotations

import json

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
