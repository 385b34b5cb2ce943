"""Fuzz: network and program artifacts — damaged bytes, forged (re-signed) JSON edits, version
skew, missing and extra files, nesting bombs and giant integers in any JSON value (and in
``program.json``'s graph and report texts), forged ``arrays.npz`` members whose ``.npy``
headers declare huge, negative or object shapes (re-signed), and files over their size cap
(sparse).  A load either refuses with an error naming the file, or gives a network/program
that then simulates or refuses with a typed error.
"""

from __future__ import annotations

import io
import json
import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import (
    JUNK,
    bounded_outcome,
    budget,
    byte_mutations,
    huge_npy,
    json_bombs,
    outcome,
)
from hypothesis import given, note
from hypothesis import strategies as st

from backends import load, save
from backends.artifact_io import (
    MAX_ARRAYS_BYTES,
    MAX_MANIFEST_BYTES,
    canonical_json,
    render_json,
    sha256_hex,
)
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


@budget(0.35)
@given(st.sampled_from(["network", "program"]), st.data(), st.integers(0, 9))
def test_byte_damaged_artifacts(templates, kind, data, slot) -> None:
    folder = _copy(templates, kind, slot)
    victim = data.draw(st.sampled_from(_files(folder)))
    victim.write_bytes(data.draw(byte_mutations(victim.read_bytes())))
    note(f"{kind}: damaged {victim.relative_to(folder)}")
    outcome(lambda: _use(folder, kind), _culprits(folder))


@budget(0.35)
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
    _resign_reference(folder, kind, victim)
    outcome(lambda: _use(folder, kind), _culprits(folder, *values))


def _resign_reference(folder: Path, kind: str, victim: Path) -> None:
    """A program's ``program.json`` re-signed for the network manifest ``victim``'s new digest."""
    if kind == "program" and victim.parent != folder and victim.name == "manifest.json":
        program = json.loads((folder / "program.json").read_text())
        for seg in program["segments"]:
            if seg.get("network", {}).get("path") == str(victim.parent.relative_to(folder)):
                seg["network"]["manifest_sha256"] = json.loads(victim.read_text()).get(
                    "manifest_sha256")
        _resign(folder / "program.json", program)


@budget(0.1)
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


SPOT = "BOMB_GOES_HERE"


@budget(0.1)
@given(st.sampled_from(["network", "program"]), json_bombs(), st.data(), st.integers(0, 9))
def test_nesting_bombs_and_giant_numbers_in_artifact_json(templates, kind, bomb, data,
                                                          slot) -> None:
    folder = _copy(templates, kind, slot)
    victim = data.draw(st.sampled_from([p for p in _files(folder) if p.suffix == ".json"]))
    doc = json.loads(victim.read_text())
    where = data.draw(st.sampled_from(["value", "value", "graph", "report", "document"]))
    if where == "document":
        victim.write_text(bomb)
    elif where in ("graph", "report") and victim.name == "program.json":
        doc[where] = bomb  # JSON text inside the manifest: re-signed, parsed after the digest
        _resign(victim, doc)
    else:
        path = data.draw(st.sampled_from([p for p in _paths(doc)[1:]
                                          if p[-1:] != ("manifest_sha256",)]))
        try:  # a bomb json can read (shallow, small): a re-signed, canonical forgery
            doc = _edit(doc, path, "set", json.loads(bomb))
            _resign(victim, doc)
            _resign_reference(folder, kind, victim)
        except (RecursionError, ValueError):  # deep or giant: spliced into the text
            doc = _edit(doc, path, "set", SPOT)
            _resign(victim, doc)
            victim.write_text(victim.read_text().replace(f'"{SPOT}"', bomb))
    note(f"{kind}: {victim.relative_to(folder)} {where}: {bomb[:200]}")
    outcome(lambda: _use(folder, kind), _culprits(folder))


def _zip(members: dict[str, bytes], method: int) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=method) as zf:
        for name, raw in members.items():
            zf.writestr(name, raw)
    return buffer.getvalue()


@budget(0.1)
@given(st.sampled_from(["network", "program"]), huge_npy(), st.data(), st.integers(0, 9))
def test_forged_npz_members_and_oversize_files(templates, kind, member, data, slot) -> None:
    folder = _copy(templates, kind, slot)
    npy, _ = member
    action = data.draw(st.sampled_from(["member", "member", "member", "oversize"]))
    if action == "oversize":  # sparse: the size alone must refuse it, unread
        victim = data.draw(st.sampled_from(_files(folder)))
        limit = MAX_ARRAYS_BYTES if victim.suffix == ".npz" else MAX_MANIFEST_BYTES
        with victim.open("r+b") as f:
            f.truncate(limit + 1)
        note(f"{kind}: {victim.relative_to(folder)} grown to {limit + 1} bytes")
        bounded_outcome(lambda: _use(folder, kind), _culprits(folder))
        return
    arrays = data.draw(st.sampled_from([p for p in _files(folder) if p.name == "arrays.npz"]))
    with zipfile.ZipFile(arrays) as zf:
        members = {info.filename: zf.read(info) for info in zf.infolist()}
    name = data.draw(st.sampled_from(sorted(members)))
    members[name] = npy
    raw = _zip(members, data.draw(st.sampled_from([zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED])))
    arrays.write_bytes(raw)
    manifest_path = arrays.with_name("manifest.json")
    manifest = json.loads(manifest_path.read_text())
    manifest["arrays"].update(sha256=sha256_hex(raw), n_bytes=len(raw))
    _resign(manifest_path, manifest)  # re-signed: the npz reader must catch it
    _resign_reference(folder, kind, manifest_path)
    note(f"{kind}: {arrays.relative_to(folder)} member {name} = {npy[:120]!r}")
    bounded_outcome(lambda: _use(folder, kind), _culprits(folder))
