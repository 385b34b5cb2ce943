"""Bounded NIR reading (backends.nir.reading): each way a hostile .nir file broke ``nir.read``
(recursion, KeyError, TypeError, AssertionError, UnicodeDecodeError, h5py OSError, a
decompression bomb) is now one ``ArtifactError`` naming the file, the node path and the limit."""

from __future__ import annotations

import h5py
import nir
import numpy as np
import pytest

from backends.nir.reading import ReadBounds, read_nir
from ir.errors import ArtifactError


@pytest.fixture
def good(tmp_path):
    path = tmp_path / "good.nir"
    nir.write(path, nir.NIRGraph.from_list(nir.Linear(weight=np.ones((2, 3))),
                                           nir.IF(r=np.ones(2), v_threshold=np.ones(2),
                                                  v_reset=np.zeros(2))))
    return path


def _refused(path, match: str, **kw) -> str:
    with pytest.raises(ArtifactError, match=match) as info:
        read_nir(path, **kw)
    message = str(info.value)
    assert str(path) in message and "\n" not in message
    return message


def test_a_good_file_reads_as_nir_read_does(good) -> None:
    ours, theirs = read_nir(good), nir.read(good)
    assert set(ours.nodes) == set(theirs.nodes) and sorted(ours.edges) == sorted(theirs.edges)
    np.testing.assert_array_equal(ours.nodes["linear"].weight, theirs.nodes["linear"].weight)


def test_a_hard_link_cycle_is_named(good) -> None:
    with h5py.File(good, "a") as f:
        f["node/nodes/linear/loop"] = f["node/nodes"]  # a hard link back up the path
    with pytest.raises(RecursionError):
        nir.read(good)
    _refused(good, r"/node/nodes/linear/loop: links back to a group on its own path")


def test_deep_nesting_stops_at_max_depth(good) -> None:
    with h5py.File(good, "a") as f:
        g = f["node/nodes/linear"]
        for _ in range(3000):
            g = g.create_group("g")
    _refused(good, r"/node/nodes/linear/g(/g)*: groups nest deeper than max_depth=32")


def test_a_hard_link_diamond_is_refused_at_the_first_repeat(good) -> None:
    with h5py.File(good, "a") as f:  # 2^20 paths through 20 groups
        top = f["node/nodes/linear"].create_group("d0")
        for k in range(1, 21):
            nxt = top.create_group(f"d{k}")
            top["twin"] = nxt
            top = nxt
    _refused(good, r"/d0/d1/.*: is a second hard link to an object already read")


def test_the_number_of_objects_is_bounded(good) -> None:
    _refused(good, r"more than max_objects=5 ", bounds=ReadBounds(max_objects=5))


def test_a_decompression_bomb_is_refused_from_its_declared_shape(good) -> None:
    with h5py.File(good, "a") as f:
        del f["node/nodes/linear/weight"]
        f["node/nodes/linear"].create_dataset("weight", shape=(3, 10**8), dtype="f8",
                                              compression="gzip", fillvalue=0.0)
    assert good.stat().st_size < 100_000
    _refused(good, r"/node/nodes/linear/weight: shape \(3, 100000000\) declares 300000000 "
                   r"entries, over max_dataset_entries=16777216")


def test_the_total_of_declared_bytes_is_bounded(good) -> None:
    _refused(good, r"max_total_bytes=16 ", bounds=ReadBounds(max_total_bytes=16))


def test_a_missing_field_is_a_typed_error_not_a_key_error(good) -> None:
    with h5py.File(good, "a") as f:
        del f["node/nodes/linear/weight"]
    _refused(good, r"/node/nodes/linear: nir refuses the Linear node \(KeyError|TypeError")


def test_an_unknown_field_and_an_unknown_type(good) -> None:
    with h5py.File(good, "a") as f:
        f["node/nodes/linear/extra"] = 1
        del f["node/nodes/if/type"]
        f["node/nodes/if"].create_dataset("type", data="Bogus", dtype=h5py.string_dtype())
    _refused(good, r"/node/nodes/(if|linear): nir refuses the (Bogus|Linear) node")


def test_wrong_dtypes_and_shapes(good) -> None:
    with h5py.File(good, "a") as f:
        del f["node/nodes/if/r"]
        f["node/nodes/if"].create_dataset("r", data=np.ones(2, dtype=[("a", "f8")]))
    _refused(good, r"/node/nodes/if/r: dtype .* is not a number, boolean or string")
    with h5py.File(good, "a") as f:
        del f["node/nodes/if/r"]
        f["node/nodes/if/r"] = np.ones(5)  # parameters of different lengths
    _refused(good, r"/node/nodes/if: nir refuses the IF node \(AssertionError")
    with h5py.File(good, "a") as f:
        for field in ("r", "v_threshold", "v_reset"):
            del f[f"node/nodes/if/{field}"]
            f[f"node/nodes/if/{field}"] = np.ones(5)  # 5 neurons after a 2-row Linear
    _refused(good, r"/node: nir refuses the NIRGraph node \(ValueError: .*type")


def test_a_string_that_is_not_utf8(good) -> None:
    with h5py.File(good, "a") as f:
        del f["node/nodes/linear/type"]
        f["node/nodes/linear/type"] = np.bytes_(b"Lin\xffear")
    _refused(good, r"/node/nodes/linear/type: a string is not UTF-8")


def test_soft_links_and_a_missing_root(good, tmp_path) -> None:
    with h5py.File(good, "a") as f:
        f["node/nodes/linear/soft"] = h5py.SoftLink("/node/nodes/if")
    _refused(good, r"/node/nodes/linear/soft: is a SoftLink")
    with h5py.File(good, "a") as f:
        del f["node/nodes/linear/soft"], f["node/type"]
        f["node/type"] = np.zeros(0)  # an array where the root's type string belongs
    _refused(good, r"/node: the root's type is '\[\]', not 'NIRGraph'")
    empty = tmp_path / "empty.nir"
    h5py.File(empty, "w").close()
    _refused(empty, r"/node: missing: not a NIR file")


def test_truncated_and_non_hdf5_files(good, tmp_path) -> None:
    data = good.read_bytes()
    cut = tmp_path / "cut.nir"
    cut.write_bytes(data[: len(data) // 2])
    _refused(cut, r"not a readable HDF5 NIR file \(OSError")
    text = tmp_path / "text.nir"
    text.write_text("name: not hdf5\n")
    _refused(text, r"not a readable HDF5 NIR file")
    _refused(tmp_path / "absent.nir", r"cannot read")
    _refused(tmp_path, r"is not a file")
    _refused(good, r"over max_file_bytes=10", bounds=ReadBounds(max_file_bytes=10))
