"""Fuzz: NIR files (``backends.nir.import_nir`` → ``backends.save``) — byte damage of exported
files (a network with every neuron form, a compact one, a two-network program); HDF5 edits
by h5py: deep nesting, hard-link cycles and diamonds, soft and external links, datasets
declaring huge gzip'd shapes, wrong dtypes, deleted members, strings that are not UTF-8,
junk in the radarsnn metadata.  An import either refuses with a typed error naming the file
or a node, or gives networks that serialise as artifacts; peak memory grows by at most 512 MiB."""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from fuzz_support import JUNK, bounded_outcome, budget, byte_mutations
from hypothesis import given, note
from hypothesis import strategies as st

from backends.artifact import network_files
from backends.nir import export_network, export_program, import_nir, write_nir
from compiler.compile import compile_graph
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir import Graph

MAX_GROWTH = 512 << 20


def _network() -> SpikingNetwork:
    return SpikingNetwork(
        name="fuzz-nir", n_steps=12,
        populations=[Population(id="x/in", shape={"rep": 2, "i": 3}, source=True),
                     Population(id="a/out", shape={"rep": 2, "o": 3},
                                params=NeuronParams(du=0.5, dv=0.25, v_th=1.0, reset="value",
                                                    phases=(Phase(start_step=0, bias=0.1),))),
                     Population(id="b/out", shape={"rep": 2, "o": 3},
                                params=NeuronParams(du=0.0, v_th=2.0, reset="fire_once"))],
        projections=[MatrixProjection(id="a/w", source="x/in", target="a/out", contract=("i",),
                                      produce=("o",), weights=np.arange(9.0).reshape(3, 3) / 8,
                                      delays=np.arange(9).reshape(3, 3) % 3),
                     StencilProjection(id="b/k", source="a/out", target="b/out", axes=("o",),
                                       kernel=np.array([0.5, 1.0, -0.25]), edge=("wrap",))],
        encoders=[Encoder(port="x", population="x/in",
                          code=LatencyCode(t_max=12, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="y", population="b/out", kind="spike_time")])


@pytest.fixture(scope="module")
def templates():
    root = Path(tempfile.mkdtemp(prefix="fuzz-nir-"))
    made = {}
    for kind, max_weights in (("network", 1 << 24), ("compact", 8)):
        graph, report = export_network(_network(), max_weights=max_weights)
        made[kind] = write_nir(graph, report, root / f"{kind}.nir").path
    chain = Graph.from_dict({"name": "fuzz-prog", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": 16}},
        {"id": "rng", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range",
         "keep": "positive"},
        {"id": "mag", "op": "magnitude", "input": "rng", "kind": "square"},
        {"id": "det", "op": "cfar", "input": "mag", "kind": "ca", "guard": 1, "train": 1,
         "alpha": 2.0},
        {"id": "out", "op": "output", "input": "det"}]})
    program = compile_graph(chain, "loihi2", time_steps=16, calibration_inputs={
        "x": np.random.default_rng(0).standard_normal((2, 16))})
    graph, report = export_program(program)
    made["program"] = write_nir(graph, report, root / "program.nir").path
    yield {k: Path(v) for k, v in made.items()} | {"root": root}
    shutil.rmtree(root, ignore_errors=True)


def _case(templates, kind: str, slot: int) -> Path:
    path = templates["root"] / f"case{slot}.nir"
    shutil.copyfile(templates[kind], path)
    return path


def _members(path: Path) -> tuple[list[str], list[str]]:
    groups, datasets = [], []
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: (groups if isinstance(obj, h5py.Group)
                                        else datasets).append(name))
    return groups, datasets


def _culprits(path: Path) -> list[str]:
    groups, datasets = _members(path) if path.stat().st_size else ([], [])
    names = {m.split("/nodes/")[-1].split("/")[0] for m in groups + datasets}
    return [str(path), *(f"'{n}'" for n in names), *names]


def _import(path: Path, culprits: list[str]) -> None:
    def call():
        for net in import_nir(path):
            network_files(net)  # the artifact's bytes (backends.save without the disk)
    bounded_outcome(call, culprits, max_growth=MAX_GROWTH)


@budget(0.1)
@given(st.sampled_from(["network", "compact", "program"]), st.data(), st.integers(0, 9))
def test_byte_damaged_nir_files(templates, kind, data, slot) -> None:
    path = _case(templates, kind, slot)
    culprits = _culprits(path)
    path.write_bytes(data.draw(byte_mutations(path.read_bytes())))
    _import(path, culprits)


HUGE = [(3, 10**8), (2**40,), (10**6, 10**6), (2**24 + 1,), (0,), (), (1, 0, 5)]
DTYPES = ["c16", "f2", "i1", "u8", "?", "S3", [("a", "f8")], "V8"]


def _edit(f: h5py.File, action: str, group: str, dataset: str, data) -> None:
    g = f[group]
    if action == "nest":
        for _ in range(data.draw(st.sampled_from([10, 30, 33, 100, 3000]))):
            g = g.create_group("g")
    elif action == "cycle":
        g["loop"] = f[data.draw(st.sampled_from(["/", "/node", group]))]
    elif action == "diamond":
        for k in range(data.draw(st.integers(1, 24))):
            nxt = g.create_group(f"d{k}")
            g["twin"] = nxt
            g = nxt
    elif action == "soft":
        g["link"] = data.draw(st.sampled_from([h5py.SoftLink("/node"), h5py.SoftLink("/nope"),
                                               h5py.ExternalLink("/etc/passwd", "/x")]))
    elif action == "huge":
        del f[dataset]
        shape = data.draw(st.sampled_from(HUGE))
        f.create_dataset(dataset, shape=shape, dtype="f8", fillvalue=1.0,
                         compression="gzip" if shape else None)
    elif action == "dtype":
        del f[dataset]
        dtype = np.dtype(data.draw(st.sampled_from(DTYPES)))
        f.create_dataset(dataset, data=np.zeros(data.draw(st.sampled_from([(), (3,), (2, 2)])),
                                                dtype=dtype))
    elif action == "delete":
        del f[data.draw(st.sampled_from([group, dataset]))]
    elif action == "utf8":
        del f[dataset]
        f[dataset] = np.bytes_(data.draw(st.sampled_from([b"\xff\xfe", b"Linear\x80",
                                                          b"\xed\xa0\x80"])))
    else:  # junk in a radarsnn metadata string (JSON entries, indices, the version)
        del f[dataset]
        f.create_dataset(dataset, data=json.dumps(data.draw(JUNK), allow_nan=True),
                         dtype=h5py.string_dtype())


ACTIONS = ["nest", "cycle", "diamond", "soft", "huge", "dtype", "delete", "utf8", "junk"]


@budget(0.12)
@given(st.sampled_from(["network", "compact", "program"]), st.sampled_from(ACTIONS), st.data(),
       st.integers(0, 9))
def test_hostile_hdf5_edits(templates, kind, action, data, slot) -> None:
    path = _case(templates, kind, slot)
    culprits = _culprits(path)
    groups, datasets = _members(path)
    group = "/" + data.draw(st.sampled_from(groups))
    pool = [d for d in datasets if "radarsnn" in d] if action == "junk" else datasets
    dataset = "/" + data.draw(st.sampled_from(pool))
    note(f"{action} at {group} / {dataset}")
    with h5py.File(path, "a") as f:
        _edit(f, action, group, dataset, data)
    _import(path, culprits)
