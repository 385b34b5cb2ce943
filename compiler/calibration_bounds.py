r"""Worst-case value bounds propagated from declared input bounds, one rule per op type.

With no calibration inputs, the ``calibrate`` pass bounds every node it can from
the inputs' declared largest ``|Re|``/``|Im|`` ``b`` (option ``input_bounds``, or
the ADC full scale).  Each op type's rule is its own (``Op.bound``, e.g.
:meth:`ir.ops.DFT.bound`); an op type without one says why (``Op.no_bound``).  The
table of every op's rule is derived from the op registry (:func:`ir.ops.registry.op_table`,
shown in ``docs/ir.md``).

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

from ir import Graph

__all__ = ["propagate_bounds"]


def propagate_bounds(graph: Graph, bounds: dict[str, float]) -> dict[str, float]:
    """Each node's largest ``|Re|``/``|Im|`` from the bounds of ``bounds``' nodes, in order.

    Nodes whose op has no rule (its class does not define ``bound``) or whose inputs
    are not all bounded get no entry.

    Parameters
    ----------
    graph : Graph
        The chain.
    bounds : dict of str to float
        Node id -> its bound (the graph inputs', typically).

    Returns
    -------
    dict of str to float
        Node id -> bound, in topological order.
    """
    types = graph.infer_types()
    out: dict[str, float] = {}
    for node in graph.topological_order():
        op, args = graph.op(node), graph.inputs_of(node)
        if node in bounds:
            out[node] = float(bounds[node])
        elif type(op).has_bound() and args and all(a in out for a in args):
            out[node] = float(op.bound(node, [out[a] for a in args], [types[a] for a in args]))
    return out
