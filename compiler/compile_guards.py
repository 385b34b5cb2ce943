r"""Resource guards of the compiler: estimate memory and time from the chain's types, refuse early.

:func:`estimate_compile` reads only the inferred tensor types of a verified-able
graph (nothing is allocated) and predicts the dominant memory and time of
:func:`~compiler.compile.compile_graph`; :func:`check_compile` refuses a chain
over the limits with a :class:`~ir.errors.BudgetError` naming the largest node,
the estimate, the limit and how to proceed.  The limits are the compile options
``max_memory_bytes`` and ``max_time_s`` (defaults :data:`MAX_MEMORY_BYTES`,
:data:`MAX_TIME_S`, for a 24 GB, 2-core machine).

Model, per node with ``n`` elements, ``b`` bytes per element (16 complex, 8
real, 1 mask) and ``P`` spike parts per value (4 complex, 2 signed amplitude,
1 otherwise):

.. math::

    M = \sum_{\text{nodes}} \Big(\underbrace{2\,n\,b}_{\text{calibration values}}
        + \underbrace{B_{neuron}\,n\,P}_{\text{lowered neurons}}\Big)
        + \sum_{\text{dft, linear}} \underbrace{3 \cdot 8\,(n_{in} P)(n_{out} P)}_{\text{dense
        weights and their quantized copies}}

with :data:`NEURON_BYTES` per neuron (populations, demand and placement
arrays); time is :data:`NEURON_S` per neuron plus :data:`WEIGHT_S` per weight
entry.  On the CARRADA chain (820 k neurons, 8.4 MB of DFT weights) the model
predicts 290 MB and 2.5 s where ``compile_graph(..., target="loihi2")`` grows the
process by 160 MB in 1.1 s: conservative, within a factor of 2.

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"nodes": [
...     {"id": "x", "op": "input", "shape": {"a": 1000}},
...     {"id": "f", "op": "dft", "input": "x", "axis": "a"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> e = estimate_compile(g)
>>> e.largest, e.per_node   # f: 2·1000·16 + 200·1000·4 + 3·8·(1000·2)(1000·4)
('f', {'x': 416000, 'f': 192832000, 'o': 832000})
>>> check_compile(g, max_memory_bytes=10**8)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ir.errors.BudgetError: chain 'chain': compiling needs about 194 MB (over max_memory_bytes=100 MB)...
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from ir import Graph
from ir.errors import BudgetError, CompileError
from ir.limits import check_limit, check_value_sizes, human_bytes
from ir.ops import DFT, Linear
from ir.types import TensorType

__all__ = ["MAX_MEMORY_BYTES", "MAX_TIME_S", "NEURON_BYTES", "NEURON_S", "WEIGHT_S",
           "CompileEstimate", "check_compile", "estimate_compile", "limits_from_options"]

#: Default memory limit of one compilation: 8 GiB (a third of a 24 GB machine).
MAX_MEMORY_BYTES = 8 << 30
#: Default limit on the estimated compile time, s.
MAX_TIME_S = 3600.0
#: Compile-time bytes per lowered neuron (populations, demand and placement arrays).
NEURON_BYTES = 200
#: Compile time per lowered neuron, s (split and place dominate).
NEURON_S = 2e-6
#: Compile time per dense weight entry, s (build, quantize, count).
WEIGHT_S = 1e-8
_WEIGHT_COPIES = 3
#: Op types lowered to weight matrices (compiler.lowering.dft_common.op_weights).
_WEIGHT_OPS = (DFT, Linear)


@dataclass(frozen=True)
class CompileEstimate:
    """What compiling a chain is expected to cost.

    Attributes
    ----------
    per_node : dict of str to int
        Estimated bytes per node id.
    memory_bytes : int
        Their sum.
    time_s : float
        Estimated compile time.
    """

    per_node: dict[str, int] = field(default_factory=dict)
    memory_bytes: int = 0
    time_s: float = 0.0

    @property
    def largest(self) -> str | None:
        """The node with the largest share (None for an empty graph)."""
        return max(self.per_node, key=self.per_node.__getitem__, default=None)


def _parts(t: TensorType) -> int:
    if t.complex:
        return 4
    return 2 if t.domain in ("amplitude", "db") else 1


def estimate_compile(graph: Graph) -> CompileEstimate:
    """Estimate memory and time of compiling ``graph`` (see the module for the model).

    Parameters
    ----------
    graph : Graph
        The chain; its types are inferred (nothing is allocated).

    Returns
    -------
    CompileEstimate

    Raises
    ------
    IRError
        If the graph's types cannot be inferred (as :meth:`Graph.infer_types`).
    """
    types = graph.infer_types()
    per_node: dict[str, int] = {}
    time_s = 0.0
    for node, t in types.items():
        op = graph.op(node)
        neurons = t.size * _parts(t)
        total = 2 * t.nbytes + NEURON_BYTES * neurons
        time_s += NEURON_S * neurons
        if isinstance(op, _WEIGHT_OPS):
            src = types[graph.inputs_of(node)[0]]
            axis = op.axis
            out_axis = getattr(op, "out_axis", None) or axis
            entries = (src.axes[axis] * _parts(src)) * (t.axes[out_axis] * _parts(t))
            total += _WEIGHT_COPIES * 8 * entries
            time_s += WEIGHT_S * entries
        per_node[node] = int(total)
    return CompileEstimate(per_node=per_node, memory_bytes=sum(per_node.values()),
                           time_s=time_s)


def limits_from_options(options: Mapping[str, object] | None) -> tuple[int | None, float | None]:
    """``(max_memory_bytes, max_time_s)`` from compile options (defaults where absent).

    Raises
    ------
    CompileError
        A limit that is not a positive finite number or None (NaN would switch the guard
        off), naming the option and the value.

    Examples
    --------
    >>> limits_from_options({"max_time_s": 60})
    (8589934592, 60.0)
    >>> limits_from_options({"max_memory_bytes": -1})
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: compile option: max_memory_bytes=-1 must be a positive finite number \
of bytes, or None (no limit)
    """
    options = options or {}
    return (check_limit("max_memory_bytes", options.get("max_memory_bytes", MAX_MEMORY_BYTES),
                        "bytes", where="compile option", error=CompileError),
            check_limit("max_time_s", options.get("max_time_s", MAX_TIME_S), "s",
                        where="compile option", error=CompileError))


def check_compile(graph: Graph, *, max_memory_bytes: int | None = MAX_MEMORY_BYTES,
                  max_time_s: float | None = MAX_TIME_S) -> CompileEstimate:
    """Refuse a chain whose compile estimate exceeds a limit (``None``: no limit).

    Parameters
    ----------
    graph : Graph
        The chain.
    max_memory_bytes : int or None
        Memory limit (default :data:`MAX_MEMORY_BYTES`).
    max_time_s : float or None
        Limit on the estimated compile time (default :data:`MAX_TIME_S`).

    Returns
    -------
    CompileEstimate

    Raises
    ------
    BudgetError
        Over a limit, naming the largest node, the estimate, the limit and the fixes.
    CompileError
        A limit that is not a positive finite number or None.
    IRError
        If the graph's types cannot be inferred.
    """
    max_memory_bytes = check_limit("max_memory_bytes", max_memory_bytes, "bytes",
                                   where=f"chain {graph.name!r}", error=CompileError)
    max_time_s = check_limit("max_time_s", max_time_s, "s", where=f"chain {graph.name!r}",
                             error=CompileError)
    est = estimate_compile(graph)
    node = est.largest
    if node is None:
        return est
    # whatever the limits: a value no array can hold (an n_fft of 2**63) is never compiled
    check_value_sizes(graph, graph.infer_types(), graph, max_memory_bytes=None,
                      error=BudgetError)
    t = graph.infer_types()[node]
    what = (f"node {node!r} ({graph.op(node).op}) at {human_bytes(est.per_node[node])}: a "
            f"{dict(t.axes)} {'complex' if t.complex else 'real'} value")
    fixes = (f"shrink its axes or n_fft, compute it on the host (motifs={{{node!r}: 'host'}}), "
             "or raise the compile option")
    if max_memory_bytes is not None and est.memory_bytes > max_memory_bytes:
        raise BudgetError(f"chain {graph.name!r}: compiling needs about "
                          f"{human_bytes(est.memory_bytes)} (over max_memory_bytes="
                          f"{human_bytes(max_memory_bytes)}); the largest part is {what}; "
                          f"{fixes} max_memory_bytes", node=node)
    if max_time_s is not None and est.time_s > max_time_s:
        raise BudgetError(f"chain {graph.name!r}: compiling would take about {est.time_s:.3g} s "
                          f"(over max_time_s={max_time_s:g}); the largest part is {what}; "
                          f"{fixes} max_time_s", node=node)
    return est
