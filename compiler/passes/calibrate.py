r"""The ``calibrate`` pass: value ranges per node, from which motifs set encoders and thresholds.

Policies (compile option ``calibration``, the pass's field ``policy``):

``static``
    Ranges from the calibration inputs (``CompileContext.calibration_inputs``,
    one array per graph input, optionally with a leading frames axis) or, if
    none are given, propagated from declared input bounds (option
    ``input_bounds``: input node id → largest ``|Re|``/``|Im|``).  Nothing adapts
    at run time; the motifs scale by ``headroom`` (option ``headroom``, default 1).
    The pass's fields hold these options; ``compile_graph`` sets them
    (:func:`compiler.compile.default_pipeline`).
``per-input``
    Each graph input's encoder normalises every slice over the axes that the
    chain later mixes (those contracted by ``dft``/``linear`` or summed by
    ``sum``) so its largest part is 1; ranges are measured on the normalised
    calibration inputs (or propagated from bound 1).  Decoded values are in
    those normalised units.

Measured records also hold per-axis profiles (``axis_max``, ``axis_quantiles``,
see :mod:`compiler.calibration`): what per-bin stage gains are set from.

Calibration inputs are evaluated with :func:`ir.interpreter.evaluate` and the
context's evaluators (``CompileContext.evaluators``), so a chain holding an op of
the user's own is measured like any other.  Bound propagation (no calibration
inputs): one rule per op type in :mod:`compiler.calibration_bounds` (``window`` keeps
the bound, ``dft``/``linear`` give ``max_k Σ_l (|Re W_kl| + |Im W_kl|) · b`` …); the
ops without one say why there.

Examples
--------
>>> import numpy as np
>>> from ir import Graph
>>> from compiler.passes.base import CompileContext
>>> from compiler.program import CompiledProgram
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"sample": 4}},
...     {"id": "f", "op": "dft", "input": "a", "axis": "sample"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> ctx = CompileContext(calibration_inputs={"a": np.array([1.0, 0.0, -1.0, 0.0])})
>>> rec = Calibrate().apply(ctx, CompiledProgram(graph=g)).records["calibrate"]
>>> rec.policy, rec.nodes["f"].max_re, rec.nodes["f"].max_im
('static', 2.0, 0.0)
>>> rec = Calibrate(policy="per-input").apply(CompileContext(), CompiledProgram(graph=g))
>>> rec = rec.records["calibrate"]
>>> rec.source, rec.nodes["a"].normalize_axes, rec.nodes["f"].max_part
('bounds', ('sample',), 4.0)
"""

from __future__ import annotations

import copy
import logging
import math
import warnings
from dataclasses import dataclass, replace

import networkx as nx
import numpy as np

from compiler.calibration import Calibration, NodeCalibration, measure, second_moment
from compiler.calibration_bounds import propagate_bounds
from compiler.compile_guards import MAX_MEMORY_BYTES
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from compiler.snn.coding import normalize_values
from ir import Graph
from ir.errors import CompileError
from ir.interpreter import evaluate
from ir.ops import DFT, AdcInput, Linear, Sum, Window

__all__ = ["Calibrate", "CalibrationWarning", "adc_full_scales", "mixed_axes"]

log = logging.getLogger(__name__)
_POLICIES = ("static", "per-input")


def mixed_axes(graph: Graph, node: str) -> tuple[str, ...]:
    """Axes of input ``node`` that a downstream ``dft``/``linear``/``sum`` mixes (input order).

    Examples
    --------
    >>> from compiler.chains import range_doppler_chain
    >>> from radar.config import preset
    >>> mixed_axes(range_doppler_chain(preset("carrada")), "adc")
    ('rx', 'chirp', 'sample')
    """
    axes = graph.infer_types()[node].names
    below = nx.descendants(graph.to_networkx(), node)
    mixed = {graph.op(n).axis for n in below if isinstance(graph.op(n), DFT | Linear | Sum)}
    return tuple(a for a in axes if a in mixed)


class CalibrationWarning(UserWarning):
    """A compile whose ranges are a worst case, not measured (no calibration data)."""


def adc_full_scales(graph: Graph) -> dict[str, float]:
    """``{adc input: full scale}`` for the ``adc_input`` nodes that declare one.

    The default bounds of a static compile without calibration data: every stage's
    range is propagated from the ADC's full scale, so nothing a real capture holds
    can exceed it (the price: a scene far below full scale uses few of the code's
    levels, ``docs/fourier.md``).

    Examples
    --------
    >>> from compiler.chains import range_doppler_chain
    >>> from radar.config import preset
    >>> adc_full_scales(range_doppler_chain(preset("carrada")))
    {'adc': 32768.0}
    """
    return {n: float(op.full_scale) for n in graph.input_ids()
            if isinstance(op := graph.op(n), AdcInput) and op.full_scale is not None}


def _frames(graph: Graph, inputs: dict) -> tuple[list[dict[str, np.ndarray]], int]:
    types = graph.infer_types()
    arrays, counts = {}, set()
    for node in graph.input_ids():
        if node not in inputs:
            raise CompileError(f"calibration: no calibration array for input {node!r}; give one "
                               f"per graph input ({graph.input_ids()})", node=node)
        x, want = np.asarray(inputs[node]), types[node].shape
        if x.shape == want:
            x = x[None]
        elif x.shape[1:] != want:
            raise CompileError(f"calibration: input {node!r} has shape {x.shape}; expected {want} "
                               f"or (n_frames, *{want})", node=node)
        arrays[node] = x
        counts.add(x.shape[0])
    if len(counts) != 1:
        raise CompileError(f"calibration: inputs disagree on the number of frames {sorted(counts)}")
    n = counts.pop()
    return [{k: v[i] for k, v in arrays.items()} for i in range(n)], n


def _propagate(graph: Graph, bounds: dict[str, float]) -> dict[str, NodeCalibration]:
    """Node records from :func:`compiler.calibration_bounds.propagate_bounds`."""
    types = graph.infer_types()
    out = propagate_bounds(graph, bounds)
    return {n: NodeCalibration(node=n, max_re=b, max_im=b if types[n].complex else 0.0,
                               max_abs=b * (math.sqrt(2) if types[n].complex else 1.0),
                               max_l1=2 * b if types[n].complex else b, min=-b, max=b,
                               source="bounds") for n, b in out.items()}


def _add_second_moments(graph: Graph, types: dict, per_node: dict, nodes: dict) -> None:
    """The second moments a linear consumer's weight rounding needs (integer targets)."""
    for node in graph.topological_order():
        op = graph.op(node)
        if not isinstance(op, Window | DFT | Linear) or not graph.inputs_of(node):
            continue
        src = graph.inputs_of(node)[0]
        if src not in per_node or src not in nodes or op.axis in nodes[src].second_moments:
            continue
        t = types[src]
        h = second_moment(np.stack(per_node[src]), 1 + t.index(op.axis),
                          "re_im_signed" if t.complex else "signed")
        if h is not None:
            nodes[src].second_moments[op.axis] = h


@dataclass(frozen=True)
class Calibrate(Pass):
    """Measure (or bound) every node's range under the chosen policy; see the module docstring.

    Records :class:`~compiler.calibration.Calibration` as ``records["calibrate"]``.

    Under ``static`` with neither calibration inputs nor ``input_bounds`` nothing
    is measured (``source="none"``, no node records): chains without calibrated
    motifs compile unchanged, and a motif that needs a range raises a
    :class:`~ir.errors.CompileError` naming the node and the fix.

    Attributes
    ----------
    policy : {"static", "per-input"}
        The calibration policy (compile option ``calibration``).
    headroom : float
        Factor >= 1 the motifs scale the measured ranges by (option ``headroom``).
    input_bounds : tuple of (str, float)
        Input node id and its largest ``|Re|``/``|Im|``, used when no calibration
        inputs are given (option ``input_bounds``).
    max_memory_bytes : int or None
        The compile memory limit the calibration evaluation runs under (option
        ``max_memory_bytes``; None: no limit).

    Raises
    ------
    CompileError
        For an unknown policy or a bad headroom (when the pass is made).
    """

    name = "calibrate"
    policy: str = "static"
    headroom: float = 1.0
    input_bounds: tuple[tuple[str, float], ...] = ()
    max_memory_bytes: int | None = MAX_MEMORY_BYTES

    def __post_init__(self) -> None:
        if self.policy not in _POLICIES:
            raise CompileError(f"calibration={self.policy!r} is not a policy; use 'static' or "
                               "'per-input'")
        if not (math.isfinite(self.headroom) and self.headroom >= 1.0):
            raise CompileError(f"headroom={self.headroom} must be a finite number >= 1")

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        reuse = self._reused(ctx, program)
        if reuse is not None:
            program.records.calibration = reuse
            log.info("policy %s: the ranges measured for an earlier attempt on the same "
                     "chain and frames, reused", self.policy)
            return program
        program = self._measure(ctx, program)
        if ctx.calibrations is not None and program.records.calibration.source == "inputs":
            ctx.calibrations.append((self._memo_key(ctx, program),
                                     copy.deepcopy(program.records.calibration)))
        return program

    def _memo_key(self, ctx: CompileContext, program: CompiledProgram, *,
                  kept: bool = True) -> tuple:
        """What a measured calibration depends on besides the frames (the same list's): the
        chain, this pass's fields and the target (compared by value); the chain copied for
        a key that is ``kept``, the program's own for a lookup."""
        graph = copy.deepcopy(program.graph) if kept else program.graph
        return (graph, self.policy, float(self.headroom), ctx.target,
                self.max_memory_bytes, tuple(sorted(ctx.calibration_inputs)))

    def _reused(self, ctx: CompileContext, program: CompiledProgram) -> Calibration | None:
        """A copy of a calibration measured with the same key, if ``ctx`` keeps any."""
        if not ctx.calibrations or not ctx.calibration_inputs:
            return None
        key = self._memo_key(ctx, program, kept=False)
        for held, calibration in ctx.calibrations:
            if held[1:] == key[1:] and held[0] == key[0]:
                return copy.deepcopy(calibration)
        return None

    def _measure(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        policy, headroom = self.policy, float(self.headroom)
        graph, types = program.graph, program.graph.infer_types()
        norm = {n: mixed_axes(graph, n) if policy == "per-input" else ()
                for n in graph.input_ids()}
        if ctx.calibration_inputs:
            limit = self.max_memory_bytes
            frames, n_frames = _frames(graph, dict(ctx.calibration_inputs))
            per_node: dict[str, list[np.ndarray]] = {}
            for frame in frames:
                frame = {k: normalize_values(v, tuple(types[k].index(a) for a in norm[k]))
                         for k, v in frame.items()}
                for node, value in evaluate(graph, frame, registry=ctx.evaluators,
                                            max_memory_bytes=limit).items():
                    if value.dtype != bool:
                        per_node.setdefault(node, []).append(value)
            nodes = {n: measure(n, np.stack(v), normalize_axes=norm.get(n, ()),
                                axes=types[n].names) for n, v in per_node.items()}
            if ctx.target.number_format.integer:
                _add_second_moments(graph, types, per_node, nodes)
            for n in graph.input_ids():  # compile-time only: the lowering's measured choices
                if n in per_node and n in nodes:
                    nodes[n] = replace(nodes[n], frames=np.stack(per_node[n]))
            source = "inputs"
        else:
            given = dict(self.input_bounds)
            bounds = ({n: 1.0 for n in graph.input_ids()} if policy == "per-input"
                      else given or adc_full_scales(graph))
            if bounds and policy == "static" and not given:
                warnings.warn(
                    f"calibrate: no calibration data; every range is bounded from the ADC full "
                    f"scale of {', '.join(f'{k!r} ({v:g})' for k, v in bounds.items())} — a worst "
                    "case: a scene far below full scale keeps few code levels (docs/fourier.md); "
                    "give calibration_inputs (CLI: -c) for a usable chain",
                    CalibrationWarning, stacklevel=2)
            nodes = _propagate(graph, bounds)
            nodes = {n: c if n not in norm else
                     NodeCalibration(**{**c.__dict__, "normalize_axes": norm[n]})
                     for n, c in nodes.items()}
            source, n_frames = ("bounds" if bounds else "none"), 0
        program.records.calibration = Calibration(policy=policy, headroom=headroom,
                                                 source=source, nodes=nodes, n_frames=n_frames)
        log.info("policy %s, ranges from %s (%d frame(s)), %d node(s) ranged, "
                 "headroom %g", policy, source, n_frames, len(nodes), headroom)
        return program
