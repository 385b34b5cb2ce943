r"""The ``fuse-linear`` pass: fold windows and diagonal scalings into the next linear map.

Rewrites, applied until none matches (every rewrite keeps the graph's value
exactly up to rounding, checked against :func:`ir.interpreter.evaluate` in the tests):

1. ``window(kind) → dft`` on the same axis, the DFT without a window: the DFT
   takes the window (its ``window`` field, :math:`X_k = \sum_n w_n x_n e^{…}`) and
   reads the window's input.  A ``rect`` window is simply removed.
2. ``window → linear`` on the same axis: the matrix columns are scaled,
   :math:`A' = A\,\mathrm{diag}(w)`.
3. ``a → b`` with ``a``, ``b`` each a ``dft`` or ``linear``, ``b`` along ``a``'s output
   axis, ``a`` read by ``b`` only: replaced by one ``linear`` :math:`W_b W_a` when
   that has fewer non-zero weights than the two (a diagonal ``a`` always
   qualifies; two dense DFTs never do).

The surviving node keeps the id of the later one, so consumers are unchanged.
Every other node keeps its op object: the pass rebuilds the graph from the
graph's own ops (never by re-reading a chain file with the built-in op
registry), so a chain holding ops of the user's own passes through untouched.
``records["fuse-linear"]`` lists every rewrite: ``{"rule", "into", "folded",
"synapses_before", "synapses_after"}``.

Examples
--------
>>> from ir import Graph
>>> from compiler.passes.base import CompileContext
>>> from compiler.program import CompiledProgram
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"sample": 8}},
...     {"id": "w", "op": "window", "input": "a", "axis": "sample", "kind": "hann"},
...     {"id": "f", "op": "dft", "input": "w", "axis": "sample", "keep": "positive"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> p = FuseLinear().apply(CompileContext(), CompiledProgram(graph=g))
>>> p.graph.topological_order(), p.graph.op("f").window
(['a', 'f', 'o'], 'hann')
>>> p.records["fuse-linear"][0]["rule"]
'window-into-dft'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from compiler.lowering.dft_common import op_weights
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from ir import Graph
from ir.ops import DFT, Linear, Op, Window
from radar.windows import window_coefficients

__all__ = ["FuseLinear"]

def _linear_op(w: np.ndarray, axis: str, out_axis: str, *, complex_out: bool) -> Linear:
    """The ``linear`` op applying ``w``; it keeps the replaced node's output type, so a
    complex output stays complex even when the fused product has no imaginary part."""
    imag = w.imag.tolist() if complex_out or np.any(w.imag != 0) else None
    return Linear(axis=axis, out_axis=out_axis, matrix=w.real.tolist(), matrix_imag=imag)


def _nnz(w: np.ndarray) -> int:
    return int(np.count_nonzero(w))


def _rebuilt(graph: Graph, folded: str, keep_folded: bool, into: str, op: Op,
             source: str) -> Graph:
    """``graph`` with node ``into`` applying ``op`` to ``source``, and ``folded`` dropped
    unless ``keep_folded``; every other node (op object, inputs, order) as it was."""
    out = Graph(graph.name)
    for node_id in graph:
        if node_id == folded and not keep_folded:
            continue
        if node_id == into:
            out.add(op, inputs=source, id=node_id)
        else:
            out.add(graph.op(node_id), inputs=graph.inputs_of(node_id), id=node_id)
    return out


@dataclass(frozen=True)
class FuseLinear(Pass):
    """Fold windows, diagonal scalings and cheap linear chains; see the module docstring."""

    name = "fuse-linear"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        graph = program.graph
        record: list[dict[str, Any]] = []
        while (rewritten := self._rewrite_once(graph, record)) is not None:
            graph = rewritten
        if record:
            graph.verify()
            program.graph = graph
        program.records.rewrites = record
        return program

    def _rewrite_once(self, graph: Graph, record: list[dict[str, Any]]) -> Graph | None:
        """The graph after the first rewrite that applies (appended to ``record``), or None."""
        types = graph.infer_types()
        for b_id in graph.topological_order():
            op_b = graph.op(b_id)
            if not isinstance(op_b, DFT | Linear):
                continue
            (a_id,) = graph.inputs_of(b_id)
            op_a = graph.op(a_id)
            only_b = graph.consumers_of(a_id) == [b_id]
            in_axis = op_b.axis
            if isinstance(op_a, Window) and op_a.axis == in_axis:
                (source,) = graph.inputs_of(a_id)
                n_in = types[source].axes[in_axis]
                if isinstance(op_b, DFT) and op_b.window is None:
                    new = op_b if op_a.kind == "rect" else DFT.model_validate(
                        {**op_b.model_dump(), "window": op_a.kind})
                    rule = "window-into-dft"
                elif isinstance(op_b, Linear):
                    taps = window_coefficients(op_a.kind, n_in)
                    w = op_weights(op_b, n_in, node=b_id) * taps[None, :]
                    new = _linear_op(w, in_axis, op_b.out_axis or in_axis,
                                     complex_out=types[b_id].complex)
                    rule = "window-into-linear"
                else:
                    continue
                record.append({"rule": rule, "into": b_id, "folded": a_id,
                               "synapses_before": None, "synapses_after": None})
                return _rebuilt(graph, a_id, not only_b, b_id, new, source)
            if (isinstance(op_a, DFT | Linear) and only_b
                    and (op_a.out_axis or op_a.axis) == in_axis):
                (source,) = graph.inputs_of(a_id)
                w_a = op_weights(op_a, types[source].axes[op_a.axis], node=a_id)
                w_b = op_weights(op_b, types[a_id].axes[in_axis], node=b_id)
                w = w_b @ w_a
                before, after = _nnz(w_a) + _nnz(w_b), _nnz(np.round(w, 12))
                if after >= before:
                    continue
                new = _linear_op(w, op_a.axis, op_b.out_axis or in_axis,
                                 complex_out=types[b_id].complex)
                record.append({"rule": "linear-chain", "into": b_id, "folded": a_id,
                               "synapses_before": before, "synapses_after": after})
                return _rebuilt(graph, a_id, False, b_id, new, source)
        return None
