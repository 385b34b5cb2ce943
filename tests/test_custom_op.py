"""A user's op end to end: ``scale`` (y = c·x) through compile_graph and run_program.

The op, its reference implementation and its lowering rule live here, outside the package,
in copies of the registries (docs/howto-op.md): nothing is registered globally.

S-FT bound (docs/fourier.md, time-coded S-FT with the constant charging schedule): every
real and imaginary part of the range S-FT's decoded value is within
``N·X/(2T) + s/2`` of the DFT — the input rounding of ``N`` samples, ``X/(2T)`` each
(encoder range ``X``, ``T`` steps), and half an output step ``s`` — plus the 24-bit weight
rounding (``≤ N·X·2⁻²⁴``, covered by ``1e-6``), as long as the calibration covers the
inputs.  ``scale`` multiplies the value and so the bound by ``|c|``: with motif ``decoder``
its decoder's scale is ``c·s``; with motif ``host`` the host runs ``c·x`` on the decoded
spectrum (exactly).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Literal

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pydantic import Field

from backends import load_program, save_program
from backends.reference import run_program, simulate
from compiler.compile import compile_graph
from compiler.lowering import SpikeValue, default_registry
from compiler.passes import CompileContext
from compiler.passes.fuse_linear import FuseLinear
from compiler.program import CompiledProgram
from ir import (
    EVAL_REGISTRY,
    OP_REGISTRY,
    ArtifactError,
    ChainFileError,
    CompileError,
    Graph,
    IRError,
    Op,
    TensorType,
    evaluate,
)
from ir.errors import SimulationError
from radarsnn.cli import main

N = 8  # samples of the range DFT


class Scale(Op):
    r"""Multiply every element by a constant: :math:`y = c\,x` (test-only op)."""

    op: Literal["scale"] = "scale"
    factor: float = Field(allow_inf_nan=False)

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude",), allow_complex=True)
        return t


def evaluate_scale(node_id, op, args, types):
    return op.factor * args[0]


def lower_scale(ctx, node_id, op, inputs):
    (src,) = inputs
    if not isinstance(src, SpikeValue) or src.decoder.kind == "spiked":
        raise CompileError(f"node {node_id!r} (scale): motif 'decoder' needs a value-coded "
                           "spiking input", node=node_id)
    d = src.decoder
    decoder = d.model_copy(update={"port": node_id, "node": node_id,
                                   "scale": op.factor * d.scale,
                                   "offset": op.factor * d.offset,
                                   "missing": op.factor * d.missing})
    return dataclasses.replace(src, node=node_id, type=ctx.types[node_id], decoder=decoder,
                               code={})


OPS = {**OP_REGISTRY, "scale": Scale}
EVALUATORS = {Scale: evaluate_scale}
LOWERING = default_registry().copy()
LOWERING.register(Scale, "decoder", lower_scale, default=True)


def scaled_chain(factor: float = 0.5, *, window: str | None = None) -> Graph:
    """x → [window →] dft → scale → magnitude → out."""
    nodes = [{"id": "x", "op": "input", "shape": {"sample": N}}]
    src = "x"
    if window is not None:
        nodes.append({"id": "win", "op": "window", "input": "x", "axis": "sample",
                      "kind": window})
        src = "win"
    nodes += [{"id": "rng", "op": "dft", "input": src, "axis": "sample", "out_axis": "range"},
              {"id": "half", "op": "scale", "input": "rng", "factor": factor},
              {"id": "mag", "op": "magnitude", "input": "half"},
              {"id": "out", "op": "output", "input": "mag"}]
    return Graph.from_dict({"name": "scaled-range", "nodes": nodes}, registry=OPS)


TONE = np.cos(2 * np.pi * np.arange(N) / N)  # bins 1 and N-1 hold N/2 = 4 each
TONES = np.cos(2 * np.pi * np.outer(np.arange(1, 5), np.arange(N)) / N)
_W = np.exp(-2j * np.pi * np.outer(np.arange(N), np.arange(N)) / N)
#: The inputs |x| <= 1 that make each part of the DFT largest: calibrating on them
#: covers every input in [-1, 1]^N (no saturation).
WORST = np.where(np.concatenate([_W.real, _W.imag]) >= 0, 1.0, -1.0)


def compile_scaled(graph: Graph, motif: str, target="loihi2", calibration=TONES, **kwargs):
    motifs = {"half": "host"} if motif == "host" else None
    # run on its own calibration data: the encoder's range is the calibrated one
    kwargs["options"] = {"encoder_headroom": 1, **kwargs.get("options", {})}
    return compile_graph(graph, target, motifs=motifs, registry=LOWERING,
                         evaluators=EVALUATORS, calibration_inputs={"x": calibration}, **kwargs)


def sft_bound(program: CompiledProgram, factor: float) -> float:
    """The module docstring's bound on each part of ``half`` (constant charging schedule)."""
    (net,) = program.networks
    code = net.encoders[0].code
    (dec,) = net.decoders
    step = abs(dec.scale) if dec.port == "half" else abs(factor * dec.scale)
    assert dec.kind == "spike_time" and not dec.table  # the bound's schedule
    return abs(factor) * N * code.x_max / (2 * code.t_max) + step / 2 + 1e-6


def max_part_error(a: np.ndarray, b: np.ndarray) -> float:
    d = np.asarray(a) - np.asarray(b)
    return float(max(np.abs(d.real).max(), np.abs(d.imag).max()))


# -- the worked example of docs/howto-op.md ------------------------------------------------


@pytest.mark.parametrize("motif", ["decoder", "host"])
def test_worked_example_compiles_with_calibration_and_runs(motif: str) -> None:
    graph = scaled_chain(0.5)
    program = compile_scaled(graph, motif)
    assert list(program.records["timings"])[:5] == ["verify", "fuse-linear", "static-split",
                                                   "calibrate", "lower"]
    assert program.records["calibrate"].source == "inputs"
    # the Nyquist tone (-1)^n puts all N = 8 in bin 4: 0.5·8 (bins 1-3 hold 4 each)
    assert program.records["calibrate"].nodes["half"].max_part == pytest.approx(4.0)
    assert program.records["lower"]["motifs"]["half"] == motif
    assert program.evaluators == EVALUATORS
    spiking_end = "half" if motif == "decoder" else "rng"
    assert [(s.kind, s.inputs, s.outputs) for s in program.segments][0] == (
        "spiking", ["x"], [spiking_end])
    assert program.host_nodes == (["mag", "out"] if motif == "decoder"
                                  else ["half", "mag", "out"])
    assert program.records["report"].data["totals"]["neurons"] == 32  # the S-FT's alone
    result = run_program(program, {"x": TONE})
    # hand-worked: |0.5·DFT(cos)| = 0.5·4 in bins 1 and 7, 0 elsewhere
    np.testing.assert_allclose(result.outputs["out"], [0, 2, 0, 0, 0, 0, 0, 2], atol=1e-3)
    if motif == "host":  # evaluate_scale ran on the decoded spectrum
        np.testing.assert_array_equal(result.values["half"], 0.5 * result.values["rng"])
    with pytest.raises(SimulationError, match="simulate runs one spiking network, not a "
                                              "CompiledProgram; run a compiled program with"):
        simulate(program, {"x": TONE})  # a program runs with run_program (issue 20, item 5)


def test_worked_example_totals_are_the_sfts_alone() -> None:
    with_scale = compile_scaled(scaled_chain(0.5), "decoder")
    plain = compile_graph(Graph.from_dict({"name": "r", "nodes": [
        {"id": "x", "op": "input", "shape": {"sample": N}},
        {"id": "rng", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
        {"id": "out", "op": "output", "input": "rng"}]}), "loihi2",
        calibration_inputs={"x": TONES})
    totals = with_scale.records["report"].data["totals"]
    assert totals == plain.records["report"].data["totals"]  # scale adds no neuron or synapse


@pytest.mark.parametrize("motif", ["decoder", "host"])
@given(factor=st.floats(0.05, 4.0), negative=st.booleans(),
       x=arrays(np.float64, N, elements=st.floats(-1.0, 1.0)))
def test_scale_matches_evaluate_within_the_sft_bound(motif, factor, negative, x) -> None:
    c = -factor if negative else factor
    graph = scaled_chain(c)
    program = compile_scaled(graph, motif, target=None, calibration=WORST,
                             options={"charging": "constant"})
    values = run_program(program, {"x": x}).values
    golden = evaluate(graph, {"x": x}, registry=EVALUATORS)
    assert max_part_error(values["half"], golden["half"]) <= sft_bound(program, c)
    if motif == "host":
        np.testing.assert_array_equal(values["half"], c * values["rng"])


def test_decoder_motif_equals_c_times_the_decoded_sft() -> None:
    """Exact up to float rounding: the same spikes, read with a decoder ``c`` times larger."""
    x = np.array([0.3, -1.0, 0.25, 0.9, -0.5, 0.0, 0.75, -0.125])
    c = -1.75
    graph = scaled_chain(c)
    kw = {"calibration": WORST, "options": {"charging": "constant", "output_spikes": "time"}}
    on_spikes = run_program(compile_scaled(graph, "decoder", **kw), {"x": x}).values
    on_host = run_program(compile_scaled(graph, "host", **kw), {"x": x}).values
    np.testing.assert_allclose(on_spikes["half"], c * on_host["rng"], rtol=1e-12, atol=1e-12)


# -- fuse-linear keeps the user's op --------------------------------------------------------


def test_fuse_linear_folds_around_the_user_op_and_keeps_its_object() -> None:
    graph = scaled_chain(0.5, window="hann")
    folded = FuseLinear().apply(CompileContext(), CompiledProgram(graph=graph))
    assert folded.graph.topological_order() == ["x", "rng", "half", "mag", "out"]
    assert folded.records["fuse-linear"][0]["rule"] == "window-into-dft"
    assert folded.graph.op("rng").window == "hann"
    assert folded.graph.op("half") is graph.op("half")  # not re-read from a chain file
    x = {"x": np.linspace(-1.0, 1.0, N)}
    np.testing.assert_allclose(evaluate(folded.graph, x, registry=EVALUATORS)["out"],
                               evaluate(graph, x, registry=EVALUATORS)["out"], atol=1e-12)


def test_windowed_chain_with_the_op_compiles_and_runs() -> None:
    graph = scaled_chain(2.0, window="hann")
    program = compile_scaled(graph, "decoder", calibration=WORST,
                             options={"charging": "constant"})
    assert [r["folded"] for r in program.records["fuse-linear"]] == ["win"]
    assert "win" not in program.graph
    x = np.linspace(-1.0, 1.0, N)
    golden = evaluate(graph, {"x": x}, registry=EVALUATORS)
    half = run_program(program, {"x": x}).values["half"]
    assert max_part_error(half, golden["half"]) <= sft_bound(program, 2.0)


# -- typed errors naming the op ------------------------------------------------------------


def test_chain_file_with_the_op_needs_its_registry(tmp_path, capsys) -> None:
    path = tmp_path / "scaled.yaml"
    path.write_text(scaled_chain().to_yaml())
    fix = r"registry=\{\*\*ir\.OP_REGISTRY, 'scale': ItsClass\}"
    for read in (lambda: Graph.from_yaml(path), lambda: compile_graph(path)):
        with pytest.raises(ChainFileError, match=r"node 'half': unknown op 'scale'; .*" + fix
                           ) as info:
            read()
        assert info.value.node == "half"
    assert Graph.from_yaml(path, registry=OPS) == scaled_chain()
    assert main(["validate", str(path)]) != 0
    assert "unknown op 'scale'" in capsys.readouterr().err


def test_saved_program_with_the_op_is_refused_on_load(tmp_path, capsys) -> None:
    program = compile_scaled(scaled_chain(), "decoder")
    folder = save_program(program, tmp_path / "prog")  # data only: saving works
    with pytest.raises(ArtifactError, match=r"program\.json: .*node 'half': unknown op 'scale'"
                                            r".*program artifacts .* know the built-in ops"
                       ) as info:
        load_program(folder)
    assert info.value.node == "half"
    np.save(tmp_path / "x.npy", TONE)
    assert main(["run", str(folder), "-i", f"x={tmp_path / 'x.npy'}"]) == 1
    assert "unknown op 'scale'" in capsys.readouterr().err


def test_host_node_without_implementation_is_refused_at_compile_time() -> None:
    graph = scaled_chain()
    with pytest.raises(CompileError, match=r"node 'half' \(scale\) runs on the host, but Scale "
                                           r"has no reference implementation.*"
                                           r"evaluators=\{Scale: function\}") as info:
        compile_graph(graph, None, motifs={"half": "host"}, registry=LOWERING,
                      options={"input_bounds": {"x": 1.0}})
    assert info.value.node == "half"
    # calibration evaluates the graph: the op needs its implementation there too
    with pytest.raises(IRError, match=r"node 'half' \(scale\): no implementation for Scale; "
                                      r"pass \{Scale: function\}"):
        compile_graph(graph, None, registry=LOWERING, calibration_inputs={"x": TONES})


@pytest.mark.parametrize(("evaluators", "match"), [
    ({"scale": evaluate_scale}, r"key 'scale' is not an op class"),
    ({Scale: 3.0}, r"the implementation of Scale is a float, not a function"),
    ([(Scale, evaluate_scale)], r"evaluators must be a mapping .*; got list"),
])
def test_malformed_evaluators_are_refused(evaluators, match) -> None:
    with pytest.raises(CompileError, match=match):
        compile_graph(scaled_chain(), None, registry=LOWERING, evaluators=evaluators)


def test_run_program_without_the_implementation_names_the_node() -> None:
    program = compile_scaled(scaled_chain(), "host")
    program.evaluators = {}  # e.g. a program assembled by hand
    with pytest.raises(IRError, match=r"node 'half' \(scale\): no implementation for Scale"):
        run_program(program, {"x": TONE})


# -- no leakage ------------------------------------------------------------------------------


def test_default_registries_are_untouched_and_calls_do_not_leak() -> None:
    before = (dict(EVAL_REGISTRY), dict(OP_REGISTRY))
    graph = scaled_chain()
    first = compile_scaled(graph, "host")
    assert (dict(EVAL_REGISTRY), dict(OP_REGISTRY)) == before
    assert Scale not in EVAL_REGISTRY and "scale" not in OP_REGISTRY
    assert default_registry().motifs(Scale) == ["host"]
    fresh = CompileContext()
    assert fresh.evaluators == {} and fresh.evaluators is not CompileContext().evaluators
    # a later call without evaluators knows nothing of Scale …
    with pytest.raises(CompileError, match="Scale has no reference implementation"):
        compile_graph(graph, None, motifs={"half": "host"}, options={"input_bounds": {"x": 1}})
    # … records none for a chain without new ops …
    tiny = Graph.from_dict({"nodes": [{"id": "a", "op": "input", "shape": {"r": 2}},
                                      {"id": "o", "op": "output", "input": "a"}]})
    assert "evaluators" not in compile_graph(tiny, None).records
    # … and the first program still runs with its own
    out = run_program(first, {"x": TONE}).outputs["out"]
    np.testing.assert_allclose(out, [0, 2, 0, 0, 0, 0, 0, 2], atol=1e-3)


# -- the op's meaning on its class ------------------------------------------------------------


class OwnScale(Scale):
    """``Scale`` with its meaning on the class: no evaluators anywhere."""

    def evaluate(self, node_id, args, types):
        return self.factor * args[0]

    def bound(self, node_id, bounds, types):
        """``|c|`` times the bound."""
        return abs(self.factor) * bounds[0]


def test_an_op_class_with_its_own_meaning_compiles_and_runs_without_evaluators() -> None:
    ops = {**OP_REGISTRY, "scale": OwnScale}
    graph = Graph.from_dict(scaled_chain().to_dict(), registry=ops)
    assert isinstance(graph.op("half"), OwnScale)
    lowering = default_registry().copy()
    lowering.register(OwnScale, "decoder", lower_scale, default=True)
    golden = evaluate(graph, {"x": TONE})
    assert golden["half"].tolist() == (0.5 * golden["rng"]).tolist()
    # no calibration inputs: the bounds propagate through OwnScale.bound from input_bounds
    program = compile_graph(graph, None, motifs={"half": "host"}, registry=lowering,
                            options={"input_bounds": {"x": 1.0}})
    assert program.evaluators == {} and "half" in program.host_nodes
    half = program.records.calibration.nodes["half"]  # 0.5 · the 8-point DFT's 4·(1 + √2)
    assert half.source == "bounds" and half.max_re == pytest.approx(2 * (1 + np.sqrt(2)))
    values = run_program(program, {"x": TONE}).values
    assert np.array_equal(values["half"], 0.5 * values["rng"])
    assert OwnScale not in EVAL_REGISTRY
