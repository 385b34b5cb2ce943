"""Fuzz: generated code — networks whose ids, ports, name and meta are hostile strings are
emitted, parsed (every identifier plain ASCII, no hostile text outside string constants),
imported and run in-process against the reference simulator; damaged artifacts are
refused by the emitter with an error naming the file.
"""

from __future__ import annotations

import ast
import importlib
import re
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import HOSTILE_STRINGS, budget, byte_mutations, outcome
from hypothesis import given, note
from hypothesis import strategies as st

from backends import save
from backends.emit import emit_numpy
from backends.reference import simulate
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)

IDS = st.one_of(st.sampled_from([s for s in HOSTILE_STRINGS if s]),
                st.text(min_size=1, max_size=20))
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _network(ids: list[str], name: str) -> SpikingNetwork:
    src, mid, w1, w2, port_in, port_a, port_b, node = ids
    return SpikingNetwork(
        name=name, n_steps=10, meta={"note": name},
        populations=[Population(id=src, shape={"i": 3}, source=True, origin={"node": node}),
                     Population(id=mid, shape={"h": 2}, origin={"node": node},
                                params=NeuronParams(du=0.0, v_th=1.5, reset="fire_once"))],
        projections=[MatrixProjection(id=w1, source=src, target=mid, contract=("i",),
                                      produce=("h",), weights=np.array([[1.0, 0.5]] * 3),
                                      origin={"node": w2})],
        encoders=[Encoder(port=port_in, population=src,
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port=port_a, population=mid, kind="spike_time", t_ref=8.0),
                  Decoder(port=port_b, population=mid, kind="count")])


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-emit-") as tmp:
        sys.path.insert(0, tmp)
        try:
            yield Path(tmp)
        finally:
            sys.path.remove(tmp)


def _check_sources(pkg: Path, hostile: list[str]) -> None:
    for path in pkg.glob("*.py"):
        tree = ast.parse(path.read_text("ascii"))
        for node in ast.walk(tree):
            names = [getattr(node, attr) for attr in ("id", "name", "arg", "attr", "asname")
                     if isinstance(getattr(node, attr, None), str)]
            for name in names:
                assert IDENTIFIER.fullmatch(name), (path.name, name)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
                assert node.func.id not in ("__import__", "eval", "exec", "compile"), path


_COUNTER = iter(range(10**9))


@budget(0.6)
@given(st.lists(IDS, min_size=8, max_size=8, unique=True), IDS,
       st.lists(st.floats(0, 1.5), min_size=3, max_size=3))
def test_hostile_ids_emit_run_and_match(folder, ids, name, x) -> None:
    src, mid, w1, w2, port_in, port_a, port_b, node = ids
    if len({port_a, port_b}) < 2:
        return
    net = outcome(lambda: _network(ids, name).validate(), ids + [name])
    if net is None:
        return
    pkg_name = f"fuzzpkg{next(_COUNTER)}"
    pkg = emit_numpy(net, folder, name=pkg_name)
    note(pkg_name)
    _check_sources(pkg, ids + [name])
    inputs = {port_in: np.array(x)}
    ref = simulate(net, inputs, mode="step", out_of_range="clip")
    try:
        module = importlib.import_module(pkg_name)
        got = module.run(inputs, out_of_range="clip")  # x up to 1.5: clipped like ref
    finally:
        for key in [k for k in sys.modules if k == pkg_name or k.startswith(pkg_name + ".")]:
            del sys.modules[key]
        shutil.rmtree(pkg, ignore_errors=True)
    outputs = got[0] if isinstance(got, tuple) else got
    assert sorted(outputs) == sorted(ref.outputs)
    for key, value in ref.outputs.items():
        np.testing.assert_array_equal(outputs[key], value)


@budget(0.4)
@given(st.data(), st.integers(0, 9))
def test_damaged_artifacts_are_refused_by_the_emitter(folder, data, slot) -> None:
    art = folder / f"art{slot}"
    shutil.rmtree(art, ignore_errors=True)
    save(_network(["in", "mid", "w", "w2", "x", "a", "b", "n"], "net"), art)
    victim = data.draw(st.sampled_from(sorted(art.iterdir())))
    victim.write_bytes(data.draw(byte_mutations(victim.read_bytes())))
    out = folder / f"out{slot}"
    outcome(lambda: emit_numpy(art, out, name="pkg"), [str(art), str(victim)])
    shutil.rmtree(out, ignore_errors=True)
