r"""The ``fuse-linear`` pass: fold windows and diagonal scalings into the next linear map.

Rewrites, applied until none matches (every rewrite keeps the graph's value
exactly up to rounding, checked against :func:`ir.evaluate.evaluate` in the tests):

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
from radar.windows import window_coefficients

__all__ = ["FuseLinear"]

_LINEAR = ("dft", "linear")


def _linear_node(node_id: str, like: dict[str, Any], w: np.ndarray, axis: str,
                 out_axis: str, *, complex_out: bool) -> dict[str, Any]:
    """The ``linear`` node replacing ``node_id``; it keeps the replaced node's output type, so
    a complex output stays complex even when the fused product has no imaginary part."""
    node = {"id": node_id, "op": "linear", "input": like["input"], "axis": axis,
            "out_axis": out_axis, "matrix": w.real.tolist()}
    if complex_out or np.any(w.imag != 0):
        node["matrix_imag"] = w.imag.tolist()
    return node


def _nnz(w: np.ndarray) -> int:
    return int(np.count_nonzero(w))


@dataclass(frozen=True)
class FuseLinear(Pass):
    """Fold windows, diagonal scalings and cheap linear chains; see the module docstring."""

    name = "fuse-linear"

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        data = program.graph.to_dict()
        record: list[dict[str, Any]] = []
        while self._rewrite_once(data, record):
            pass
        if record:
            graph = Graph.from_dict(data)
            graph.verify()
            program.graph = graph
        program.records[self.name] = record
        return program

    def _rewrite_once(self, data: dict[str, Any], record: list[dict[str, Any]]) -> bool:
        graph = Graph.from_dict(data)
        types = graph.infer_types()
        nodes = {n["id"]: n for n in data["nodes"]}
        for b_id in graph.topological_order():
            b = nodes[b_id]
            if b["op"] not in _LINEAR or "input" not in b:
                continue
            a = nodes[b["input"]]
            only_b = graph.consumers_of(a["id"]) == [b_id]
            in_axis = b["axis"]
            if a["op"] == "window" and a["axis"] == in_axis:
                w_in = types[a["input"]]
                taps = window_coefficients(a.get("kind", "hann"), w_in.axes[in_axis])
                op_b = graph.op(b_id)
                if b["op"] == "dft" and b.get("window") is None:
                    new = dict(b, input=a["input"])
                    if a.get("kind", "hann") != "rect":
                        new["window"] = a.get("kind", "hann")
                    rule = "window-into-dft"
                elif b["op"] == "linear":
                    w = op_weights(op_b, w_in.axes[in_axis], node=b_id) * taps[None, :]
                    new = _linear_node(b_id, dict(b, input=a["input"]), w, in_axis,
                                       b.get("out_axis") or in_axis,
                                       complex_out=types[b_id].complex)
                    rule = "window-into-linear"
                else:
                    continue
                self._replace(data, a, b, new, only_b)
                record.append({"rule": rule, "into": b_id, "folded": a["id"],
                               "synapses_before": None, "synapses_after": None})
                return True
            if a["op"] in _LINEAR and only_b and (a.get("out_axis") or a["axis"]) == in_axis:
                t_a = types[a["input"]]
                w_a = op_weights(graph.op(a["id"]), t_a.axes[a["axis"]], node=a["id"])
                w_b = op_weights(graph.op(b_id), types[a["id"]].axes[in_axis], node=b_id)
                w = w_b @ w_a
                before, after = _nnz(w_a) + _nnz(w_b), _nnz(np.round(w, 12))
                if after >= before:
                    continue
                new = _linear_node(b_id, dict(b, input=a["input"]), w, a["axis"],
                                   b.get("out_axis") or in_axis,
                                   complex_out=types[b_id].complex)
                self._replace(data, a, b, new, True)
                record.append({"rule": "linear-chain", "into": b_id, "folded": a["id"],
                               "synapses_before": before, "synapses_after": after})
                return True
        return False

    @staticmethod
    def _replace(data: dict[str, Any], a: dict, b: dict, new: dict, drop_a: bool) -> None:
        out = []
        for n in data["nodes"]:
            if n is a and drop_a:
                continue
            out.append(new if n is b else n)
        data["nodes"] = out
