"""Fuzz: chain files (YAML/JSON) mutated from valid chains — read, verify, estimate, evaluate.

Mutations: junk in any field (wrong types, NaN/Inf, huge/zero/negative sizes, hostile
strings), missing/extra fields and nodes, unknown ops, self-loops, cycles, duplicate and
unknown ids, axis mix-ups, byte-level damage of the file (truncation, flipped and
inserted bytes), and hostile documents spliced into any field: alias bombs, recursive
aliases, nesting far past the bound, keys equal as values, integers of 4 301+ digits and
values no constructor builds.  A valid result must round-trip and (when small) evaluate.
"""

from __future__ import annotations

import copy
import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from fuzz_support import JUNK, budget, byte_mutations, json_bombs, outcome, yaml_bombs
from hypothesis import given, note
from hypothesis import strategies as st
from test_ir_properties import chains

from compiler.compile_guards import estimate_compile
from ir import Graph
from ir.interpreter import evaluate
from ir.ops import OP_REGISTRY

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {p.name: yaml.safe_load(p.read_text()) for p in sorted(
    (ROOT / "examples" / "chains").glob("*.yaml"))}
PARAM_KEYS = sorted({k for cls in OP_REGISTRY.values() for k in cls.model_fields} | {
    "id", "op", "input", "inputs", "bogus"})
SMALL = 4096  # evaluate chains whose values all have at most this many elements


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-chain-") as tmp:
        yield Path(tmp)


def _ids(doc: object) -> list[str]:
    nodes = doc.get("nodes") if isinstance(doc, dict) else None
    if not isinstance(nodes, list):
        return []
    return [str(n.get("id")) for n in nodes if isinstance(n, dict) and n.get("id") is not None]


@st.composite
def mutated_docs(draw: st.DrawFn) -> tuple[dict, list[str]]:
    """A chain mapping with 1-3 structural mutations, and the keys/ids they touched."""
    if draw(st.booleans()):
        doc = copy.deepcopy(EXAMPLES[draw(st.sampled_from(sorted(EXAMPLES)))])
    else:
        doc = draw(chains(max_ops=4)).to_dict()
    touched: list[str] = []
    for _ in range(draw(st.integers(1, 3))):
        nodes = doc.get("nodes") if isinstance(doc.get("nodes"), list) else None
        kind = draw(st.sampled_from(["set", "set", "delete_key", "drop_node", "dup_node",
                                     "self_loop", "cycle", "unknown_input", "swap_axis",
                                     "size", "top"]))
        if not nodes or kind == "top":
            key = draw(st.sampled_from(["name", "nodes", "extra"]))
            doc[key] = draw(JUNK)
            touched += [key, "chain"]
            continue
        i = draw(st.integers(0, len(nodes) - 1))
        node = nodes[i]
        if not isinstance(node, dict):
            continue
        touched.append(str(node.get("id")))
        if kind == "set":
            key = draw(st.sampled_from(PARAM_KEYS))
            node[key] = draw(JUNK)
            touched.append(key)
        elif kind == "delete_key" and node:
            key = draw(st.sampled_from(sorted(node)))
            del node[key]
            touched.append(key)
        elif kind == "drop_node":
            nodes.pop(i)
        elif kind == "dup_node":
            nodes.insert(draw(st.integers(0, len(nodes))), copy.deepcopy(node))
        elif kind == "self_loop":
            node["input"] = node.get("id")
            node.pop("inputs", None)
        elif kind == "cycle":
            other = nodes[draw(st.integers(0, len(nodes) - 1))]
            node.pop("inputs", None)
            node["input"] = other.get("id") if isinstance(other, dict) else "x"
        elif kind == "unknown_input":
            node["input"] = draw(st.sampled_from(["ghost", "adc", "out", "a-b", "_"]))
        elif kind == "swap_axis":
            axes = [a for n in nodes if isinstance(n, dict) and isinstance(n.get("shape"), dict)
                    for a in n["shape"]] + ["range", "doppler", "part"]
            for key in ("axis", "out_axis", "axes"):
                if key in node:
                    pick = draw(st.sampled_from(axes))
                    node[key] = [pick] if key == "axes" else pick
                    touched.append(key)
        elif kind == "size" and isinstance(node.get("shape"), dict) and node["shape"]:
            axis = draw(st.sampled_from(sorted(node["shape"])))
            node["shape"][axis] = draw(st.sampled_from([0, -1, 2**20, 2**40, 2**63, 10**30, 1.5,
                                                        "8", None, True]))
            touched += ["shape", axis]
    return doc, touched


def _read_and_check(path: Path, fmt: str) -> Graph:
    graph = Graph.from_yaml(path) if fmt == "yaml" else Graph.from_json(path)
    graph.verify()
    text = graph.to_yaml()
    assert Graph.from_yaml(text) == graph
    estimate = estimate_compile(graph)
    assert estimate.memory_bytes > 0
    types = graph.infer_types()
    if all(t.size <= SMALL for t in types.values()) and not any(
            graph.op(n).op in ("classifier", "track", "cluster") for n in graph):
        from compiler.calibration import synthetic_inputs

        inputs = synthetic_inputs(graph, seed=0)
        for node in graph.input_ids():
            t = types[node]
            if t.domain == "mask":
                inputs[node] = inputs[node] > 0
            elif t.domain == "power":
                inputs[node] = np.abs(inputs[node])
        values = evaluate(graph, inputs)
        assert set(values) == set(types)
    return graph


def _try_load(data: bytes) -> object:
    try:
        return yaml.safe_load(data.decode("utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, RecursionError):
        return None


def _dump(doc: object, fmt: str) -> bytes:
    if fmt == "json":
        return json.dumps(doc, indent=1).encode()
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True).encode()


@budget(0.4)
@given(mutated_docs(), st.sampled_from(["yaml", "json"]), st.integers(0, 9))
def test_structurally_mutated_chain_files(folder, case, fmt, slot) -> None:
    doc, touched = case
    path = folder / f"chain{slot}.{fmt}"
    path.write_bytes(_dump(doc, fmt))
    note(path.read_text(errors="replace")[:2000])
    name = doc.get("name", "chain") if isinstance(doc, dict) else None
    outcome(lambda: _read_and_check(path, fmt), [str(path), *touched, *_ids(doc), repr(name)])


@budget(0.4)
@given(st.sampled_from(sorted(EXAMPLES)), st.sampled_from(["yaml", "json"]), st.data(),
       st.integers(0, 9))
def test_byte_damaged_chain_files(folder, name, fmt, data, slot) -> None:
    doc = EXAMPLES[name]
    damaged = data.draw(byte_mutations(_dump(doc, fmt)))
    path = folder / f"damaged{slot}.{fmt}"
    path.write_bytes(damaged)
    note(repr(damaged[:2000]))
    outcome(lambda: _read_and_check(path, fmt), [str(path), *_ids(doc), *_ids(_try_load(damaged))])


SPOT = "BOMB_GOES_HERE"


@budget(0.2)
@given(st.sampled_from(sorted(EXAMPLES)), st.sampled_from(["yaml", "json"]), st.data(),
       st.integers(0, 9))
def test_alias_and_nesting_bombs_in_chain_files(folder, name, fmt, data, slot) -> None:
    doc = copy.deepcopy(EXAMPLES[name])
    where = data.draw(st.sampled_from(["name", "nodes", "node", "param", "shape", "document"]))
    node = data.draw(st.sampled_from(doc["nodes"]))
    if where in ("name", "nodes"):
        doc[where] = SPOT
    elif where == "node":
        doc["nodes"][doc["nodes"].index(node)] = SPOT
    elif where == "param":
        node[data.draw(st.sampled_from(sorted(node)))] = SPOT
    elif where == "shape":
        node["shape"] = {"range": SPOT}
    bomb = data.draw(yaml_bombs() if fmt == "yaml" else json_bombs())
    text = SPOT if where == "document" else _dump(doc, fmt).decode()
    text = text.replace(f'"{SPOT}"' if fmt == "json" else SPOT, bomb)
    path = folder / f"bomb{slot}.{fmt}"
    path.write_text(text)
    note(f"{where}: {bomb[:300]}")
    outcome(lambda: _read_and_check(path, fmt), [str(path), *_ids(doc)])
