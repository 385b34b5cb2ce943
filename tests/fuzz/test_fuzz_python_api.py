"""Fuzz: the Python API — ``compile_graph`` options and arguments, ``simulate`` /
``run_program`` keyword arguments and inputs, ``backends.save``/``load`` targets.

Compilation is the costly call, so its share of examples is small and the chain tiny; the
options are the fuzzed part (wrong types, NaN, negative/zero/huge values, unknown names).
"""

from __future__ import annotations

import contextlib
import math
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import HOSTILE_STRINGS, JUNK, budget, outcome
from hypothesis import given, note
from hypothesis import strategies as st

from backends import load, save
from backends.reference import run_program, simulate
from backends.reference.input_range import OutOfRangeWarning
from compiler.compile import EXTRA_OPTIONS, compile_graph
from ir import Graph

GRAPH = Graph.from_dict({"name": "api", "nodes": [
    {"id": "a", "op": "input", "shape": {"range": 8}, "domain": "power"},
    {"id": "c", "op": "cfar", "input": "a", "kind": "ca", "guard": 0, "train": 1, "alpha": 1.5},
    {"id": "o", "op": "output", "input": "c"}]})
X = {"a": np.linspace(0.1, 1.0, 8)}
PROGRAM = compile_graph(GRAPH, target="loihi2", calibration_inputs=X)
NETWORK = PROGRAM.networks[0]
PORT = NETWORK.encoders[0].port
VALUES = st.one_of(JUNK, st.floats(allow_nan=True), st.integers(-5, 300))
NAMES = sorted(EXTRA_OPTIONS) + ["bogus", "motifs", ""]


def _finite_outputs(outputs: dict) -> None:
    for key, value in outputs.items():
        assert np.all(np.isfinite(np.asarray(value, dtype=float))), key


@budget(0.25)
@given(st.dictionaries(st.sampled_from(NAMES), VALUES, max_size=2),
       st.one_of(st.none(), st.sampled_from([-1, 0, 1, 3, 8, 2**40, 1.5, "16", math.nan])),
       st.one_of(st.none(), st.sampled_from([-1, 0, 1, 2, 8, 64, 65, 3.5, "8"])),
       st.sampled_from([None, "loihi", "unbounded", "tpu", "x.yaml", 3, "static"]),
       st.one_of(st.none(), st.dictionaries(st.sampled_from(["c", "cfar", "a", "o", "zz"]),
                                            st.sampled_from(["host", "bogus", "", 1]),
                                            max_size=2)),
       st.sampled_from(["static", "per-input", "bogus", None]))
def test_compile_graph_options(options, time_steps, weight_bits, target, motifs,
                               calibration) -> None:
    note(f"{options} {time_steps} {weight_bits} {target} {motifs} {calibration}")
    culprits = [*map(str, options), *map(repr, options.values()), str(time_steps),
                str(weight_bits), str(target), str(calibration), *map(str, motifs or {}),
                *map(str, (motifs or {}).values()), "'c'", "'a'", "time_steps", "weight_bits",
                "calibration", "motif", "target", "profile", "option"]

    def call():
        program = compile_graph(GRAPH, target=target, motifs=motifs, calibration=calibration,
                                calibration_inputs=X, time_steps=time_steps,
                                weight_bits=weight_bits, options=options)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutOfRangeWarning)
            _finite_outputs(run_program(program, X, max_time_s=5.0).outputs)

    outcome(call, culprits)


INPUTS = st.one_of(
    st.just(X), st.just({}), st.just({"a": X["a"], "b": X["a"]}), st.just({"a": [1, [2]]}),
    st.just({"a": X["a"] * 1e6}), st.just({"a": -X["a"]}), st.just({"a": np.full(8, np.inf)}),
    st.just({"a": np.stack([X["a"]] * 3)}), st.just({"a": np.zeros((0, 8))}),
    st.just({"a": "eight"}), st.just({"a": None}), st.just({"a": X["a"].astype(complex)}),
    st.just({"a": X["a"] > 0.5}), st.just(["a"]), st.just(None))


@budget(0.5)
@given(INPUTS, st.sampled_from(["step", "closed", "auto", "fast", None, 3]),
       st.sampled_from(["float64", "int64", "float32", None]),
       st.sampled_from(["reject", "warn", "clip", "wrap", None, {PORT: "clip"}]),
       st.sampled_from([None, 1, 10**12, -1, 2**40]),
       st.sampled_from([None, 1e-9, 3600.0, -1.0]), st.booleans(), st.booleans())
def test_simulate_and_run_program_arguments(inputs, mode, arithmetic, policy, memory, time_s,
                                            record, whole_program) -> None:
    note(f"{inputs} {mode} {arithmetic} {policy} {memory} {time_s} {record} {whole_program}")
    culprits = [f"'{PORT}'", "'a'", "'b'", str(mode), str(arithmetic), str(policy),
                "max_memory_bytes", "max_time_s", "api", NETWORK.name, "mode", "arithmetic",
                "out_of_range", "inputs", "int64"]

    def call():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutOfRangeWarning)
            if whole_program:
                result = run_program(PROGRAM, inputs, mode=mode, arithmetic=arithmetic,
                                     record_spikes=record, out_of_range=policy,
                                     max_memory_bytes=memory, max_time_s=time_s)
            else:
                port_inputs = ({PORT: next(iter(inputs.values()))} if isinstance(inputs, dict)
                               and len(inputs) == 1 else inputs)
                result = simulate(NETWORK, port_inputs, mode=mode, arithmetic=arithmetic,
                                  record_spikes=record, out_of_range=policy,
                                  max_memory_bytes=memory, max_time_s=time_s)
        _finite_outputs(result.outputs)

    outcome(call, culprits)


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-api-") as tmp:
        yield Path(tmp)


@budget(0.25)
@given(st.sampled_from(["program", "network", "graph", "none"]),
       st.one_of(st.sampled_from(HOSTILE_STRINGS), st.sampled_from(
           ["ok", "/proc/x", "/dev/null", "nested/dir", "file"])),
       st.one_of(st.none(), JUNK.map(lambda v: {"k": v})))
def test_save_and_load_targets(folder, what, name, extra) -> None:
    (folder / "file").write_text("not a directory")
    obj = {"program": PROGRAM, "network": NETWORK, "graph": GRAPH, "none": None}[what]
    target = name if name.startswith("/") else folder / name

    def call():
        saved = save(obj, target, extra=extra)
        back = load(saved)
        assert type(back) is type(obj)

    outcome(call, [str(target), "extra", "graph", "network", "object", "Graph", "NoneType",
                   str(folder)])


#: Arguments of the wrong kind for any facade parameter.
WRONG = st.one_of(JUNK, st.sampled_from([GRAPH, PROGRAM, NETWORK, X, b"bytes", 3.5, object(),
                                         print, Path("/nonexistent/x")]))


#: A valid call of each facade function (its positional arguments).
VALID = {"load": ["ok"], "load_program": ["ok"], "save": [PROGRAM, "facade"],
         "save_program": [PROGRAM, "facade"], "run_program": [PROGRAM, X],
         "simulate": [NETWORK, {PORT: X["a"]}], "evaluate": [GRAPH, X],
         "check_accuracy": [PROGRAM, X], "compile_graph": [GRAPH]}


@budget(0.25)
@given(st.sampled_from(sorted(VALID)), st.data(), st.one_of(st.none(), WRONG))
def test_facade_argument_types(folder, name, data, progress) -> None:
    import radarsnn

    args = [folder / v if isinstance(v, str) else v for v in VALID[name]]
    for i in data.draw(st.lists(st.integers(0, len(args) - 1), min_size=1, max_size=2)):
        args[i] = data.draw(WRONG)  # one or two arguments of the wrong kind
    note(f"{name}{tuple(type(a).__name__ for a in args)} progress={type(progress).__name__}")
    fn = getattr(radarsnn, name)
    kwargs = {"progress": progress} if name in ("run_program", "compile_graph") else {}
    culprits = [name, "directory", "program", "graph", "inputs", "progress", "network",
                "target", "chain", "argument", "Graph", "CompiledProgram", "SpikingNetwork",
                "mapping", "path", "api", "'a'", "'o'", "save", "simulate", "calibration",
                "input", "option", "artifact", "nonexistent", str(folder), PORT]

    def call():
        with warnings.catch_warnings(), contextlib.chdir(folder):  # a relative junk path too
            warnings.simplefilter("ignore")
            fn(*args, **kwargs)

    outcome(call, culprits)
