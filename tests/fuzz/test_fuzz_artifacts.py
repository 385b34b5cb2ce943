"""Fuzz: network and program artifacts — damaged bytes, forged (re-signed) JSON edits, version
skew, missing and extra files.  A load either refuses with an error naming the file, or gives
a network/program that then simulates or refuses with a typed error.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import JUNK, budget, byte_mutations, outcome
from hypothesis import given, note
from hypothesis import strategies as st

from backends import load, save
from backends.artifact_io import canonical_json, render_json, sha256_hex
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from compiler.program import CompiledProgram
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir import Graph

NET_INPUT = {"x": np.array([[0.9, 0.1, 0.5], [0.3, 0.0, 1.0]])}
PROGRAM_INPUT = {"a": np.linspace(0.1, 1.0, 8)}


def _network() -> SpikingNetwork:
    return SpikingNetwork(
        name="fuzz-net", n_steps=12,
        populations=[Population(id="in", shape={"r": 2, "i": 3}, source=True),
                     Population(id="mid", shape={"r": 2, "h": 3},
                                params=NeuronParams(du=0.0, v_th=1.5, reset="fire_once")),
                     Population(id="out", shape={"r": 2, "h": 3},
                                params=NeuronParams(du=0.5, v_th=1.0))],
        projections=[MatrixProjection(id="w", source="in", target="mid", contract=("i",),
                                      produce=("h",), weights=np.array([[1.0, 0.5, 0.0]] * 3),
                                      delays=np.array([[0, 1, 0]] * 3)),
                     StencilProjection(id="s", source="mid", target="out", axes=("h",),
                                       kernel=np.array([0.5, 1.0, 0.5]), edge=("clip",))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="t", population="mid", kind="spike_time", t_ref=8.0),
                  Decoder(port="n", population="out", kind="count")])


def _program() -> CompiledProgram:
    graph = Graph.from_dict({"name": "fuzz-program", "nodes": [
        {"id": "a", "op": "input", "shape": {"range": 8}, "domain": "power"},
        {"id": "c", "op": "cfar", "input": "a", "kind": "ca", "guard": 0, "train": 1,
         "alpha": 1.5},
        {"id": "o", "op": "output", "input": "c"}]})
    return compile_graph(graph, target="loihi2", calibration_inputs=PROGRAM_INPUT)


@pytest.fixture(scope="module")
def templates():
    with tempfile.TemporaryDirectory(prefix="fuzz-artifact-") as tmp:
        root = Path(tmp)
        yield {"network": save(_network(), root / "network"),
               "program": save(_program(), root / "program"), "root": root}


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file())


def _copy(templates: dict, kind: str, slot: int) -> Path:
    dst = templates["root"] / f"case{slot}"
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(templates[kind], dst)
    return dst


def _resign(path: Path, manifest: dict) -> None:
    """Write ``manifest`` with a matching digest, as a forger would."""
    body = {k: v for k, v in manifest.items() if k != "manifest_sha256"}
    try:
        manifest = {**body, "manifest_sha256": sha256_hex(canonical_json(body))}
        path.write_bytes(render_json(manifest))
    except (ValueError, TypeError):  # NaN/Inf: not strict JSON; written anyway
        path.write_text(json.dumps(manifest, sort_keys=True, indent=2))


def _paths(doc: object, prefix: tuple = ()) -> list[tuple]:
    out = [prefix]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


def _edit(doc: dict, path: tuple, action: str, value: object) -> dict:
    if not path:
        return doc if action == "delete" else {"junk": value}
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    last = path[-1]
    if action == "delete":
        del parent[last]
    elif action == "insert" and isinstance(parent, dict):
        parent[f"{last}_extra"] = value
    elif action == "insert":
        parent.insert(last, value)
    else:
        parent[last] = value
    return doc


def _use(folder: Path, kind: str) -> None:
    loaded = load(folder)
    if isinstance(loaded, CompiledProgram):
        result = run_program(loaded, PROGRAM_INPUT, out_of_range="clip")
        assert set(result.outputs) == set(loaded.graph.output_ids())
    else:
        result = simulate(loaded, NET_INPUT, mode="auto", out_of_range="clip")
        assert set(result.outputs) == {d.port for d in loaded.decoders}


#: Ids of the template artifacts: an error after a successful load names one of them.
IDS = ["'x'", "'a'", "'c'", "'o'", "'in'", "'mid'", "'out'", "'w'", "'s'", "'t'", "'n'",
       "c/", "fuzz-net", "fuzz-program"]


def _culprits(folder: Path, *values: object) -> list[str]:
    return [str(folder), *(str(p) for p in _files(folder)), *IDS, *(repr(v) for v in values),
            *(str(v) for v in values if isinstance(v, str) and v)]


@budget(0.4)
@given(st.sampled_from(["network", "program"]), st.data(), st.integers(0, 9))
def test_byte_damaged_artifacts(templates, kind, data, slot) -> None:
    folder = _copy(templates, kind, slot)
    victim = data.draw(st.sampled_from(_files(folder)))
    victim.write_bytes(data.draw(byte_mutations(victim.read_bytes())))
    note(f"{kind}: damaged {victim.relative_to(folder)}")
    outcome(lambda: _use(folder, kind), _culprits(folder))


@budget(0.4)
@given(st.sampled_from(["network", "program"]), st.data(), st.integers(0, 9))
def test_forged_manifest_edits(templates, kind, data, slot) -> None:
    folder = _copy(templates, kind, slot)
    manifests = [p for p in _files(folder) if p.suffix == ".json"]
    victim = data.draw(st.sampled_from(manifests))
    doc = json.loads(victim.read_text())
    values = []
    for _ in range(data.draw(st.integers(1, 2))):
        paths = [p for p in _paths(doc) if p[-1:] != ("manifest_sha256",)]
        path = data.draw(st.sampled_from(paths))
        action = data.draw(st.sampled_from(["set", "set", "delete", "insert"]))
        value = data.draw(st.one_of(JUNK, st.sampled_from(
            ["2.0", "1.9", "0.1", "1", "radarsnn.program", "radarsnn.spiking-network",
             "networks/../../x", "/etc", "spiking", "host", "matrix", "stencil"])))
        doc = _edit(doc, path, action, value)
        values.append(value)
        note(f"{kind}: {victim.relative_to(folder)} {action} {path} = {value!r}")
    _resign(victim, doc)
    if kind == "program" and victim.parent != folder and victim.name == "manifest.json":
        program = json.loads((folder / "program.json").read_text())  # re-sign the reference too
        for seg in program["segments"]:
            if seg.get("network", {}).get("path") == str(victim.parent.relative_to(folder)):
                seg["network"]["manifest_sha256"] = json.loads(victim.read_text()).get(
                    "manifest_sha256")
        _resign(folder / "program.json", program)
    outcome(lambda: _use(folder, kind), _culprits(folder, *values))


@budget(0.2)
@given(st.sampled_from(["network", "program"]), st.data(), st.integers(0, 9))
def test_missing_extra_and_moved_files(templates, kind, data, slot) -> None:
    folder = _copy(templates, kind, slot)
    files = _files(folder)
    action = data.draw(st.sampled_from(["delete", "extra", "move", "dir", "empty_dir"]))
    victim = data.draw(st.sampled_from(files))
    if action == "delete":
        victim.unlink()
    elif action == "extra":
        (victim.parent / data.draw(st.sampled_from(["extra.npy", "x.json", ".hidden",
                                                    "arrays.npz.tmp"]))).write_bytes(b"junk")
    elif action == "move":
        victim.rename(victim.with_name(victim.name + ".bak"))
    elif action == "dir":
        victim.unlink()
        victim.mkdir()
    else:
        shutil.rmtree(folder)
        folder.mkdir()
    note(f"{kind}: {action} {victim.relative_to(folder)}")
    outcome(lambda: _use(folder, kind), _culprits(folder))
