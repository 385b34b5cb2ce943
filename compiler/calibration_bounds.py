r"""Worst-case value bounds propagated from declared input bounds, one rule per op type.

With no calibration inputs, the ``calibrate`` pass bounds every node it can from
the inputs' declared largest ``|Re|``/``|Im|`` ``b`` (option ``input_bounds``, or
the ADC full scale).  Each op type that has a bound declares its rule in
:data:`BOUND_RULES`; each that has none says why in :data:`NO_BOUND` — every op of
:data:`ir.ops.OP_REGISTRY` is in exactly one of the two (``tests/test_op_facets.py``):

========== =====================================================================
window     keeps the bound (taps ``|w| <= 1``)
dft/linear :math:`\max_k \sum_l (|\mathrm{Re}\,W_{kl}| + |\mathrm{Im}\,W_{kl}|) \cdot b`
magnitude  ``l2``: :math:`\sqrt{n}\,b`, ``l1``: :math:`n\,b`, ``square``: :math:`n\,b^2`
           (``n`` = 2 parts for a complex input, else 1)
add        the sum of the two bounds
sum        the axis length times the bound
========== =====================================================================

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"sample": 4}},
...     {"id": "f", "op": "dft", "input": "a", "axis": "sample"},
...     {"id": "m", "op": "magnitude", "input": "f", "kind": "l1"},
...     {"id": "o", "op": "output", "input": "m"}]})
>>> propagate_bounds(g, {"a": 1.0})
{'a': 1.0, 'f': 4.0, 'm': 8.0}
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from compiler.lowering.dft_common import op_weights
from ir import Graph
from ir.ops import (
    CFAR,
    DFT,
    AdcInput,
    Add,
    Classifier,
    Cluster,
    Input,
    Linear,
    Log,
    Magnitude,
    Op,
    Output,
    Sum,
    Threshold,
    Track,
    Window,
)
from ir.types import TensorType

__all__ = ["BOUND_RULES", "NO_BOUND", "BoundRule", "propagate_bounds"]

#: ``rule(node, op, in_bounds, in_types) -> bound`` of a node whose inputs all have one.
BoundRule = Callable[[str, Op, list[float], list[TensorType]], float]


def _window(node: str, op: Window, b: list[float], types: list[TensorType]) -> float:
    return b[0]


def _linear(node: str, op: DFT | Linear, b: list[float], types: list[TensorType]) -> float:
    w = op_weights(op, types[0].axes[op.axis], node=node)
    return float((np.abs(w.real) + np.abs(w.imag)).sum(axis=1).max()) * b[0]


def _magnitude(node: str, op: Magnitude, b: list[float], types: list[TensorType]) -> float:
    n = 2 if types[0].complex else 1
    return {"l2": math.sqrt(n) * b[0], "l1": n * b[0], "square": n * b[0] * b[0]}[op.kind]


def _add(node: str, op: Add, b: list[float], types: list[TensorType]) -> float:
    return b[0] + b[1]


def _sum(node: str, op: Sum, b: list[float], types: list[TensorType]) -> float:
    return types[0].axes[op.axis] * b[0]


#: The bound rule of every op type that has one.
BOUND_RULES: dict[type[Op], BoundRule] = {
    Window: _window, DFT: _linear, Linear: _linear, Magnitude: _magnitude, Add: _add, Sum: _sum,
}

#: Op types without a propagated bound, and why (their motifs need calibration inputs).
NO_BOUND: dict[type[Op], str] = {
    Input: "a graph input: bounded by the option input_bounds, not propagated",
    AdcInput: "a graph input: bounded by its ADC full scale, not propagated",
    Output: "passes its input through; nothing is lowered for it",
    Log: "no useful worst case (log of a value near 0 is unbounded below)",
    CFAR: "a comparison: a mask, not a value range",
    Threshold: "a comparison: a mask, not a value range",
    Classifier: "scores of a trained network: bounded by its calibration, not by its input",
    Cluster: "host-only: a table of detections, not a value",
    Track: "host-only: a table of tracks, not a value",
}


def propagate_bounds(graph: Graph, bounds: dict[str, float]) -> dict[str, float]:
    """Each node's largest ``|Re|``/``|Im|`` from the bounds of ``bounds``' nodes, in order.

    Nodes whose op has no rule (:data:`NO_BOUND`) or whose inputs are not all bounded
    get no entry.
    """
    types = graph.infer_types()
    out: dict[str, float] = {}
    for node in graph.topological_order():
        op, args = graph.op(node), graph.inputs_of(node)
        rule = BOUND_RULES.get(type(op))
        if node in bounds:
            out[node] = float(bounds[node])
        elif rule is not None and args and all(a in out for a in args):
            out[node] = float(rule(node, op, [out[a] for a in args], [types[a] for a in args]))
    return out
