"""Fuzz: ``.npy`` inputs — wrong dtypes and shapes, NaN/Inf, complex where real, object and
string arrays, truncated or damaged files, headers declaring huge, negative or object shapes
(with a sparse file holding 4 GiB when asked) — through ``load_arrays`` into ``simulate`` (a
network) and ``run_program`` (a program), under every out-of-range policy.
"""

from __future__ import annotations

import io
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import bounded_outcome, budget, byte_mutations, huge_npy, outcome
from hypothesis import given, note
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from backends.reference import run_program, simulate
from backends.reference.input_range import OutOfRangeWarning
from compiler.compile import compile_graph
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir import Graph
from radarsnn.cli.chain import load_arrays

NET = SpikingNetwork(
    name="npy-net", n_steps=10,
    populations=[Population(id="in", shape={"i": 3, "part": 2}, source=True),
                 Population(id="out", shape={"o": 2},
                            params=NeuronParams(du=0.0, v_th=1.0, reset="fire_once"))],
    projections=[MatrixProjection(id="w", source="in", target="out", contract=("i", "part"),
                                  produce=("o",), weights=np.ones((6, 2)))],
    encoders=[Encoder(port="x", population="in", split="signed",
                      code=LatencyCode(t_max=8, x_min=0.0, x_max=2.0))],
    decoders=[Decoder(port="y", population="out", kind="spike_time", t_ref=8.0)])
GRAPH = Graph.from_dict({"name": "npy-program", "nodes": [
    {"id": "adc", "op": "adc_input", "shape": {"sample": 4}, "complex": True},
    {"id": "f", "op": "dft", "input": "adc", "axis": "sample"},
    {"id": "m", "op": "magnitude", "input": "f", "kind": "square"},
    {"id": "o", "op": "output", "input": "m"}]})
PROGRAM = compile_graph(GRAPH, target=None, calibration_inputs={
    "adc": np.array([1.0, -0.5j, 0.25, 0.5 + 0.5j])})

DTYPES = st.sampled_from(["<f8", "<f4", "<f2", ">f8", "<i8", "|i1", "<u8", "|b1", "<c16",
                          "<c8", "<U3", "|S2", "<M8[s]", "<m8[ms]"])
SHAPES = st.sampled_from([(3,), (4,), (2, 3), (1, 3), (0, 3), (3, 1), (), (5, 2, 3), (2, 4),
                          (1, 4), (4, 1)])
SPECIALS = st.sampled_from([np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, 2.0, 2.2, 1e-300])


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-npy-") as tmp:
        yield Path(tmp)


@st.composite
def npy_files(draw: st.DrawFn) -> tuple[bytes, str]:
    """The bytes of a ``.npy`` file and what it holds."""
    kind = draw(st.sampled_from(["array", "array", "array", "object", "structured", "damaged"]))
    if kind == "object":
        buf = io.BytesIO()
        np.save(buf, np.array([1.0, "x", None], dtype=object), allow_pickle=True)
        return buf.getvalue(), kind
    if kind == "structured":
        buf = io.BytesIO()
        np.save(buf, np.zeros(3, dtype=[("a", "<f8"), ("b", "<i4")]))
        return buf.getvalue(), kind
    dtype = np.dtype(draw(DTYPES))
    shape = draw(SHAPES)
    if dtype.kind in "fc":
        values = hnp.arrays(dtype, shape, elements=st.one_of(
            SPECIALS.map(lambda v: dtype.type(v) if dtype.kind == "f" else complex(v, -v)),
            st.floats(-3, 3, width=16).map(dtype.type)))
    else:
        values = hnp.arrays(dtype, shape)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # overflow of 1e308 into float16
        array = draw(values)
    buf = io.BytesIO()
    np.save(buf, array)
    data = buf.getvalue()
    if kind == "damaged":
        data = draw(byte_mutations(data))
    return data, f"{kind} {dtype} {shape}"


def _run(target: str, path: Path, policy: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        if target == "network":
            arrays = load_arrays([f"x={path}"], ["x"], "network npy-net")
            result = simulate(NET, arrays, mode="auto", out_of_range=policy)
            assert set(result.outputs) == {"y"}
            assert np.isfinite(result.outputs["y"]).all()
        else:
            arrays = load_arrays([str(path)], ["adc"], "program npy-program")
            result = run_program(PROGRAM, arrays, out_of_range=policy)
            shape = np.shape(arrays["adc"])  # one frame, or a leading frames axis (ir.frames)
            assert result.outputs["o"].shape == ((4,) if len(shape) == 1 else (shape[0], 4))
            assert np.isfinite(result.outputs["o"]).all()


@budget(0.8)
@given(npy_files(), st.sampled_from(["network", "program"]),
       st.sampled_from(["reject", "warn", "clip"]), st.integers(0, 9))
def test_npy_inputs(folder, case, target, policy, slot) -> None:
    data, what = case
    note(what)
    path = folder / f"input{slot}.npy"
    path.write_bytes(data)
    outcome(lambda: _run(target, path, policy), [str(path), "'x'", "'adc'"])


@budget(0.2)
@given(huge_npy(), st.sampled_from(["network", "program"]), st.integers(0, 9))
def test_npy_inputs_declaring_huge_sizes(folder, case, target, slot) -> None:
    data, sparse = case
    path = folder / f"huge{slot}.npy"
    with path.open("wb") as f:
        f.write(data)
        if sparse:  # the data a 4 GiB + 8 header declares, as holes: only the header may decide
            f.truncate(sparse)
    note(f"{data[:120]!r}, {sparse} bytes")
    bounded_outcome(lambda: _run(target, path, "clip"), [str(path), "'x'", "'adc'"])
    path.unlink()
