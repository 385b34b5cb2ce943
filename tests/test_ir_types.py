"""TensorType: shapes, names, helpers and the construction rules."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from ir import IRError, TensorType


def test_axes_order_is_array_dimension_order() -> None:
    t = TensorType(axes={"rx": 4, "chirp": 64, "sample": 256}, complex=True)
    assert t.shape == (4, 64, 256)
    assert t.names == ("rx", "chirp", "sample")
    assert (t.ndim, t.size) == (3, 4 * 64 * 256)
    assert t.index("sample") == 2
    assert t.domain == "amplitude"


def test_rename_resize_drop_keep_positions() -> None:
    t = TensorType(axes={"rx": 4, "chirp": 64, "sample": 256})
    assert t.rename_axis("chirp", "doppler").names == ("rx", "doppler", "sample")
    assert t.resize_axis("sample", 128).shape == (4, 64, 128)
    assert t.drop_axis("rx").axes == {"chirp": 64, "sample": 256}
    assert t.rename_axis("rx", "rx") == t


def test_replace_revalidates() -> None:
    t = TensorType(axes={"a": 2}, complex=True)
    with pytest.raises(IRError, match="only 'amplitude' may be complex"):
        t.replace(domain="power")
    assert t.replace(complex=False, domain="power").domain == "power"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"axes": {"a": 0}}, r"field 'axes\.a': Input should be greater than 0"),
        ({"axes": {"a": -3}}, r"field 'axes\.a'"),
        ({"axes": {}}, r"field 'axes'.*at least 1 item"),
        ({"axes": {"2nd": 3}}, r"field 'axes\.2nd'.*pattern"),
        ({"axes": {"a b": 3}}, r"field 'axes\.a b'.*pattern"),
        ({"axes": {"a": 2}, "complex": True, "domain": "db"}, "only 'amplitude' may be complex"),
        ({"axes": {"a": 2}, "domain": "volts"}, r"field 'domain'"),
        ({"axes": {"a": 2}, "extra": 1}, r"field 'extra': Extra inputs are not permitted"),
    ],
)
def test_bad_types_raise_irerror(kwargs: dict, message: str) -> None:
    with pytest.raises(IRError, match=message):
        TensorType(**kwargs)


def test_helper_errors_name_the_axes() -> None:
    t = TensorType(axes={"range": 8, "doppler": 4})
    match = r"unknown axis 'rng'; available axes: \['range', 'doppler'\]"
    with pytest.raises(IRError, match=match):
        t.index("rng")
    with pytest.raises(IRError, match="duplicate axis name, 'doppler' already in"):
        t.rename_axis("range", "doppler")
    with pytest.raises(IRError, match="it is the only axis"):
        t.drop_axis("range").drop_axis("doppler")


def test_types_are_frozen() -> None:
    t = TensorType(axes={"a": 2})
    with pytest.raises(ValidationError, match="frozen"):
        t.complex = True  # type: ignore[misc]


def test_more_axes_than_max_axes_are_refused_by_verify_not_by_numpy(tmp_path):
    from ir import Graph
    from radarsnn.cli import main

    def chain(n: int) -> Graph:
        return Graph.from_dict({"nodes": [
            {"id": "x", "op": "input", "shape": {f"a{i}": 1 for i in range(n)}},
            {"id": "m", "op": "magnitude", "input": "x", "kind": "square"},
            {"id": "o", "op": "output", "input": "m"}]})

    chain(24).verify()  # MAX_AXES
    with pytest.raises(IRError, match=r"node 'x' \(input\): TensorType: 100 axes, over the limit "
                                      r"of 24 \(MAX_AXES"):
        chain(100).verify()
    path = tmp_path / "axes.yaml"
    path.write_text(chain(100).to_yaml())
    assert main(["report", str(path)]) == 1  # numpy's 64-dimension ValueError before
