"""Graph: building, reading, topological order and the structural verify rules."""

from __future__ import annotations

import pytest

from ir import DFT, Graph, Input, IRError, Magnitude, Output, Sum, TensorType, Window


def _toy() -> Graph:
    g = Graph("toy")
    g.add(Input(shape={"rx": 2, "sample": 8}), id="x")
    g.add(Window(axis="sample"), inputs=["x"], id="win")
    g.add(DFT(axis="sample", out_axis="range"), inputs=["win"], id="rng")
    g.add(Magnitude(), inputs=["rng"], id="mag")
    g.add(Sum(axis="rx"), inputs=["mag"], id="sum")
    g.add(Output(), inputs=["sum"], id="out")
    return g


def test_builder_reading_and_types() -> None:
    g = _toy()
    assert list(g) == ["x", "win", "rng", "mag", "sum", "out"]
    assert len(g) == 6 and "mag" in g and "nope" not in g
    assert g.op("rng") == DFT(axis="sample", out_axis="range")
    assert g.inputs_of("rng") == ("win",) and g.inputs_of("x") == ()
    assert g.consumers_of("rng") == ["mag"]
    assert (g.input_ids(), g.output_ids()) == (["x"], ["out"])
    g.verify()
    types = g.infer_types()
    assert list(types) == list(g)
    assert types["rng"] == TensorType(axes={"rx": 2, "range": 8}, complex=True)
    assert types["out"] == TensorType(axes={"range": 8})


def test_auto_ids_count_per_op_and_skip_taken_ones() -> None:
    g = Graph()
    g.add(Input(shape={"a": 4}), id="magnitude_0")
    assert g.add(Magnitude(), inputs="magnitude_0") == "magnitude_1"
    assert g.add(Magnitude(), inputs="magnitude_1") == "magnitude_2"
    assert g.add(Output(), inputs="magnitude_2") == "output_0"


def test_duplicate_and_malformed_ids() -> None:
    g = _toy()
    with pytest.raises(IRError, match="duplicate node id 'mag'") as info:
        g.add(Magnitude(), inputs=["rng"], id="mag")
    assert info.value.node == "mag"
    with pytest.raises(IRError, match="malformed node id '1st'"):
        g.add(Magnitude(), inputs=["rng"], id="1st")
    with pytest.raises(IRError, match="malformed input id 'a b'"):
        g.add(Magnitude(), inputs=["a b"], id="m2")
    with pytest.raises(IRError, match="expected an op, got dict"):
        g.add({"op": "magnitude"})  # type: ignore[arg-type]
    with pytest.raises(IRError, match="non-empty string"):
        Graph("")
    with pytest.raises(IRError, match=r"no node 'nope'; nodes: \['x', 'win'"):
        g.op("nope")


def test_forward_references_and_insertion_order_ties() -> None:
    g = Graph()
    g.add(Output(), inputs="b", id="out_b")  # reads a node added later
    g.add(Output(), inputs="a", id="out_a")
    g.add(Input(shape={"s": 2}), id="b")
    g.add(Input(shape={"s": 2}), id="a")
    g.verify()
    # every node after its inputs; among ready nodes, insertion order
    assert g.topological_order() == ["b", "out_b", "a", "out_a"]
    assert g.consumers_of("b") == ["out_b"]


def test_self_loop() -> None:
    g = Graph()
    g.add(Input(shape={"s": 2}), id="x")
    g.add(Magnitude(), inputs=["m"], id="m")
    with pytest.raises(IRError, match=r"node 'm' \(magnitude\): reads its own value \(self-loop\)"):
        g.verify()


def test_cycle_names_every_node_on_it() -> None:
    g = Graph("loop")
    g.add(Input(shape={"s": 4}), id="x")
    g.add(Magnitude(), inputs=["c"], id="a")
    g.add(Magnitude(), inputs=["a"], id="b")
    g.add(Magnitude(), inputs=["b"], id="c")
    g.add(Output(), inputs=["x"], id="out")
    with pytest.raises(IRError, match=r"graph 'loop': cycle through nodes") as info:
        g.topological_order()
    message = str(info.value)
    assert all(f"'{n}'" in message for n in "abc") and "'x'" not in message
    assert info.value.node in {"a", "b", "c"}


def test_unknown_input_id() -> None:
    g = _toy()
    g.add(Magnitude(), inputs=["rgn"], id="typo")
    with pytest.raises(IRError, match=r"node 'typo' \(magnitude\): unknown input id 'rgn'") as info:
        g.verify()
    assert info.value.node == "typo"


def test_dangling_node() -> None:
    g = _toy()
    g.add(Magnitude(), inputs=["rng"], id="spare")
    with pytest.raises(IRError, match=r"node 'spare' \(magnitude\): dangling") as info:
        g.verify()
    assert info.value.node == "spare"
    g.infer_types()  # types are still defined; only verify insists on outputs


def test_a_node_without_input_is_named_not_the_node_it_should_read() -> None:
    g = Graph.from_dict({"name": "bad", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 8}},
        {"id": "f", "op": "dft", "axis": "sample"},
        {"id": "o", "op": "output", "input": "f"}]})
    with pytest.raises(IRError, match=r"^node 'f' \(dft\): takes 1 input, got 0; give "
                                      r"'input: <node id>' \(nodes: \['x', 'f', 'o'\]\)$") as info:
        g.verify()  # it blamed 'x' as dangling
    assert info.value.node == "f"


def test_empty_graph() -> None:
    with pytest.raises(IRError, match="graph 'chain' has no nodes"):
        Graph().verify()


def test_type_errors_come_in_topological_order_naming_the_node() -> None:
    g = Graph()
    g.add(Output(), inputs="bad2", id="out")
    g.add(Window(axis="nope"), inputs="bad1", id="bad2")
    g.add(Window(axis="nope"), inputs="x", id="bad1")
    g.add(Input(shape={"s": 4}), id="x")
    with pytest.raises(IRError, match=r"node 'bad1' \(window\): axis 'nope'") as info:
        g.verify()
    assert info.value.node == "bad1"


def test_equality_and_networkx_copy() -> None:
    assert _toy() == _toy()
    other = _toy()
    other.name = "other"
    assert other != _toy()
    nxg = _toy().to_networkx()
    assert sorted(nxg.edges) == sorted([("x", "win"), ("win", "rng"), ("rng", "mag"),
                                        ("mag", "sum"), ("sum", "out")])
    nxg.remove_node("x")
    assert "x" in _toy()
