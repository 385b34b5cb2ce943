"""Chain files: the example chains, round trips, schema, and every load error."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

from ir import (
    CFAR,
    AdcInput,
    ChainFileError,
    Graph,
    chain_file_model,
    chain_schema,
    graph_from_yaml,
)

CHAINS = Path(__file__).resolve().parents[1] / "examples" / "chains"
EXAMPLES = sorted(CHAINS.glob("*.yaml"))


def test_the_example_chains_exist() -> None:
    assert [p.name for p in EXAMPLES] == [
        "carrada_rd_oscfar.yaml", "carrada_tracking.yaml", "seed003_range_doppler.yaml",
        "ti_range.yaml"]


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_examples_verify_round_trip_and_match_the_schema_model(path: Path) -> None:
    g = Graph.from_yaml(path)
    g.verify()
    assert g.output_ids() == ["out"]
    text = g.to_yaml()
    assert Graph.from_yaml(text) == g and Graph.from_yaml(text).to_yaml() == text
    assert Graph.from_json(g.to_json()) == g
    raw = yaml.safe_load(path.read_text())
    assert chain_file_model().model_validate(raw).name == raw["name"]


def test_carrada_example_is_the_documented_chain() -> None:
    g = Graph.from_yaml(CHAINS / "carrada_rd_oscfar.yaml")
    assert g.name == "carrada-rd-oscfar"
    assert g.op("adc") == AdcInput(shape={"rx": 4, "chirp": 64, "sample": 256}, complex=True)
    assert g.op("det") == CFAR(kind="os", axes=["range", "doppler"], guard=[3, 3], train=[4, 4],
                               k=132, alpha=1.2, edge=["clip", "wrap"])
    types = g.infer_types()
    assert types["rd"].axes == {"doppler": 64, "range": 256}
    assert types["out"].domain == "mask"


def test_dict_graph_dict_is_exact_up_to_defaults() -> None:
    raw = yaml.safe_load((CHAINS / "carrada_rd_oscfar.yaml").read_text())
    back = Graph.from_dict(raw).to_dict()
    defaults = {("win", "kind"), ("rng", "keep"), ("mag", "kind")}  # hann, all, l2
    expected = [{k: v for k, v in n.items() if (n["id"], k) not in defaults}
                for n in raw["nodes"]]
    assert back == {"name": raw["name"], "nodes": expected}


def test_seed003_and_ti_examples_hand_checked_types() -> None:
    seed = Graph.from_yaml(CHAINS / "seed003_range_doppler.yaml").infer_types()
    assert seed["rng"].axes == {"rx": 1, "chirp": 128, "range": 512}
    assert seed["rd"].axes == {"doppler": 128, "range": 512} and seed["rd"].domain == "power"
    ti = Graph.from_yaml(CHAINS / "ti_range.yaml").infer_types()
    assert ti["mag"].axes == {"range": 512} and ti["out"].domain == "mask"


def test_written_yaml_is_compact_and_ordered() -> None:
    g = Graph.from_yaml(CHAINS / "ti_range.yaml")
    lines = g.to_yaml().splitlines()
    assert lines[:2] == ["name: ti-range", "nodes:"]
    rng = "- {id: rng, op: dft, input: chirp, axis: sample, out_axis: range, keep: positive}"
    assert rng in lines
    assert json.loads(g.to_json())["nodes"][0] == {"id": "chirp", "op": "input",
                                                   "shape": {"sample": 1024}}


def test_schema_is_a_discriminated_union_requiring_op_and_id() -> None:
    schema = chain_schema()
    assert schema["$schema"].endswith("2020-12/schema")
    items = schema["properties"]["nodes"]["items"]
    assert items["discriminator"]["propertyName"] == "op"
    from ir.ops import OP_REGISTRY

    assert len(items["oneOf"]) == len(OP_REGISTRY)
    cfar = schema["$defs"]["CFARNode"]
    assert {"op", "id", "kind", "guard", "train"} <= set(cfar["required"])
    assert cfar["properties"]["pfa"]["anyOf"][0] == {
        "exclusiveMaximum": 1, "exclusiveMinimum": 0, "type": "number"}
    with pytest.raises(ValidationError):
        chain_file_model().model_validate({"nodes": [{"id": "x", "shape": {"a": 2}}]})


# -- load errors ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("data", "match", "node"),
    [
        ([1, 2], "a chain must be a mapping", None),
        ({"nodes": [], "version": 2}, r"unknown top-level keys \['version'\]", None),
        ({"name": 3, "nodes": []}, "chain 'name' must be a non-empty string", None),
        ({"name": "c"}, "'nodes' must be a list of node mappings; got NoneType", None),
        ({"nodes": ["x"]}, r"node #0: must be a mapping with 'id' and 'op'", None),
        ({"nodes": [{"op": "input"}]}, r"node #0: missing 'id'", None),
        ({"nodes": [{"id": "2x", "op": "input"}]}, r"node #0: malformed id '2x'", None),
        ({"nodes": [{"id": "x"}]}, r"node 'x': missing 'op'; valid ops: adc_input, add, cfar", "x"),
        ({"nodes": [{"id": "x", "op": "fft"}]},
         r"node 'x': unknown op 'fft'; valid ops: adc_input, add, cfar, classifier, cluster, dft, "
         r"input, linear, log, magnitude, output, sum, threshold, track, window", "x"),
        ({"nodes": [{"id": "o", "op": "output", "input": "a", "inputs": ["a"]}]},
         "give 'input' .* or 'inputs' .*, not both", "o"),
        ({"nodes": [{"id": "o", "op": "output", "inputs": "a"}]},
         "'inputs' must be a list of ids", "o"),
        ({"nodes": [{"id": "o", "op": "output", "input": 5}]}, "malformed input id 5", "o"),
        ({"nodes": [{"id": "w", "op": "window", "input": "x", "axis": "a", "size": 3}]},
         r"node 'w' \(window\): field 'size': Extra inputs are not permitted \(got 3\)", "w"),
        ({"nodes": [{"id": "w", "op": "window", "input": "x"}]},
         r"node 'w' \(window\): field 'axis': Field required$", "w"),
        ({"nodes": [{"id": "a", "op": "input", "shape": {"s": 2}},
                    {"id": "a", "op": "output", "input": "a"}]},
         r"duplicate node id 'a' \(nodes #0 and #1\)", "a"),
    ],
)
def test_from_dict_errors(data: object, match: str, node: str | None) -> None:
    with pytest.raises(ChainFileError, match=match) as info:
        Graph.from_dict(data)  # type: ignore[arg-type]
    assert info.value.node == node


def test_duplicate_yaml_keys_are_refused() -> None:
    text = "nodes:\n  - {id: x, op: input, shape: {rx: 4, rx: 8}}\n"
    with pytest.raises(ChainFileError, match=r"line 2: duplicate key 'rx'"):
        Graph.from_yaml(text)
    with pytest.raises(ChainFileError, match="duplicate key 'id'"):
        Graph.from_yaml("nodes:\n  - id: x\n    op: input\n    id: y\n")


def test_yaml_never_runs_code_and_bad_yaml_is_a_chain_file_error() -> None:
    evil = "nodes: !!python/object/apply:os.system ['echo pwned']\n"
    with pytest.raises(ChainFileError, match="invalid YAML"):
        Graph.from_yaml(evil)
    with pytest.raises(ChainFileError, match="invalid YAML"):
        Graph.from_yaml("nodes: [\n")
    with pytest.raises(ChainFileError, match="invalid YAML"):
        Graph.from_yaml("nodes: []\n---\nnodes: []\n")


def test_json_errors() -> None:
    with pytest.raises(ChainFileError, match="duplicate key 'op'"):
        Graph.from_json('{"nodes": [{"id": "x", "op": "input", "op": "output"}]}')
    with pytest.raises(ChainFileError, match="NaN is not a number a chain file may hold"):
        Graph.from_json('{"nodes": [{"id": "t", "op": "threshold", "value": NaN}]}')
    with pytest.raises(ChainFileError, match="invalid JSON"):
        Graph.from_json('{"nodes": [}')


def test_files_are_named_in_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("nodes:\n  - {id: w, op: windw, axis: a}\n")
    match = r"bad\.yaml: chain 'chain', node 'w': unknown op"
    with pytest.raises(ChainFileError, match=match) as info:
        graph_from_yaml(bad)
    assert info.value.node == "w"
    with pytest.raises(ChainFileError, match=r"missing\.yaml: cannot read the chain file"):
        Graph.from_yaml(tmp_path / "missing.yaml")
    with pytest.raises(ChainFileError, match=r"chain\.yaml: cannot read the chain file"):
        Graph.from_yaml("chain.yaml")  # a one-line str is a file name
    ok = tmp_path / "ok.yaml"
    ok.write_text("name: ok\nnodes:\n  - {id: a, op: input, shape: {r: 2}}\n"
                  "  - {id: o, op: output, input: a}\n")
    assert Graph.from_yaml(str(ok)).name == "ok"
    with pytest.raises(ChainFileError, match="must be a mapping"):
        Graph.from_yaml("- just\n- a list\n")
    with pytest.raises(ChainFileError, match="expected chain text"):
        Graph.from_yaml(b"nodes: []")  # type: ignore[arg-type]
    good = tmp_path / "good.json"
    g = Graph.from_yaml(CHAINS / "ti_range.yaml")
    good.write_text(g.to_json())
    assert Graph.from_json(good) == g


# -- hostile input: huge values in messages, alias and nesting bombs ------------------------


def _shared_tree(levels: int) -> list:
    """A list whose full ``repr`` has 2**levels leaves, built from ``levels`` shared lists."""
    tree: list = ["lol"]
    for _ in range(levels):
        tree = [tree, tree]
    return tree


@pytest.mark.parametrize("where", ["name", "id", "op", "input", "param"])
def test_messages_quote_a_huge_value_in_bounded_size(where: str) -> None:
    # 2**22 leaves: a full repr is 30 MB (2**62 leaves, from a 500-byte alias bomb, never ends)
    bomb = _shared_tree(22)
    node = {"id": "t", "op": "threshold", "input": "x", "value": 1.0}
    data: dict = {"name": "c", "nodes": [node]}
    if where == "name":
        data["name"] = bomb
    elif where == "param":
        node["value"] = bomb
    else:
        node[where] = bomb
    tracemalloc.start()
    try:
        with pytest.raises(ChainFileError) as info:
            Graph.from_dict(data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(str(info.value)) < 600 and "[[" in str(info.value)
    assert peak < 4 << 20, f"{peak} bytes allocated to describe the value"


def _laughs(levels: int, width: int = 9) -> str:
    """A "billion laughs" chain: ``width ** levels`` strings from ``levels`` short lines."""
    lines = ['name: &a ["lol"' + ', "lol"' * (width - 1) + "]"]
    anchors = "abcdefghijklmnop"
    for prev, here in zip(anchors, anchors[1:levels + 1], strict=False):
        lines.append(f"x{here}: &{here} [" + ", ".join([f"*{prev}"] * width) + "]")
    return "\n".join(lines) + "\nnodes: []\n"


def test_a_yaml_alias_bomb_is_refused_by_counting_before_it_expands(tmp_path: Path) -> None:
    bomb = tmp_path / "laughs.yaml"
    bomb.write_text(_laughs(9))  # 9**10 = 3.5e9 strings from ~500 bytes
    assert bomb.stat().st_size < 600
    with pytest.raises(ChainFileError, match=r"laughs\.yaml: line 6: the document has more "
                                             r"than 524288 YAML nodes .*MAX_YAML_NODES"):
        Graph.from_yaml(bomb)
    with pytest.raises(ChainFileError, match=r"alias \*a is inside the node it names"):
        Graph.from_yaml("name: c\nnodes: &a [*a]\n")


def test_yaml_parsing_uses_libyaml_and_refuses_files_over_the_size_and_node_caps(
        tmp_path: Path) -> None:
    from ir.parsing import MAX_YAML_NODES, YAML_LOADER
    from ir.serialize import MAX_CHAIN_FILE_BYTES

    if hasattr(yaml, "CSafeLoader"):
        assert YAML_LOADER is yaml.CSafeLoader
    assert MAX_CHAIN_FILE_BYTES == 8 << 20
    big = tmp_path / "big.yaml"
    with big.open("wb") as f:
        f.truncate(MAX_CHAIN_FILE_BYTES + 1)
    with pytest.raises(ChainFileError, match=r"big\.yaml: .*8388609 bytes, over the "
                                             r"8388608-byte limit"):
        Graph.from_yaml(big)
    many = "name: c\nnodes: [" + "1, " * MAX_YAML_NODES + "]\n"  # 1.5 MiB, no aliases
    with pytest.raises(ChainFileError, match="more than 524288 YAML nodes"):
        Graph.from_yaml(many)


@pytest.mark.parametrize("fmt", ["yaml", "json"])
def test_deeply_nested_chain_files_are_refused_without_recursion(fmt: str) -> None:
    deep = "[" * 5000 + "]" * 5000
    with pytest.raises(ChainFileError, match=r"nested deeper than 64 levels"):
        if fmt == "yaml":
            Graph.from_yaml(f"name: c\nnodes: {'[' * 65}{']' * 65}\n")
        else:
            Graph.from_json('{"name": "c", "nodes": ' + deep + "}")
    if fmt == "yaml":  # libyaml stops at 1000 levels itself: an invalid-YAML error
        with pytest.raises(ChainFileError):
            Graph.from_yaml(f"name: c\nnodes: {deep}\n")


@pytest.mark.parametrize(("keys", "dup"), [("1: a\n    1.0: b", "1.0"), ("yes: a\n    true: b",
                                           "True"), ("null: a\n    ~: b", "None")])
def test_yaml_keys_equal_as_values_are_duplicates(keys: str, dup: str) -> None:
    text = f"nodes:\n  - id: x\n    op: input\n    {keys}\n"
    with pytest.raises(ChainFileError, match=rf"line 5: duplicate key {dup} \(equal to the key "
                                             "on line 4"):
        Graph.from_yaml(text)


def test_unreadable_values_and_non_string_keys_are_chain_file_errors() -> None:
    with pytest.raises(ChainFileError, match=r"node 'x': key 1 \(int\) is not a field name"):
        Graph.from_yaml("nodes:\n  - {id: x, op: input, shape: {r: 2}, 1: 2}\n")
    with pytest.raises(ChainFileError, match=r"line 2: '1111.*' is not a readable !!int value"):
        Graph.from_yaml("name: c\nnodes: [" + "1" * 5000 + "]\n")
    with pytest.raises(ChainFileError, match=r"'2001-02-30' is not a readable !!timestamp"):
        Graph.from_yaml("name: 2001-02-30\nnodes: []\n")
    with pytest.raises(ChainFileError, match=r"a number cannot be read"):
        Graph.from_json('{"nodes": [' + "1" * 5000 + "]}")
