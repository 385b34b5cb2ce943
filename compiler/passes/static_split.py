r"""The ``static-split`` pass: the part of the signal repeating over chirps goes to the host.

A radar frame's samples carry a *static* part that is the same in every chirp
(Tx→Rx leakage, static clutter) — in the near range rows 70–110 dB above the moving
part and the noise.  Spiking stages with a ``T``-step time code resolve ``≈ 48 dB``
under the largest value of a neuron, so a range row whose static value sets its
scale loses everything else: its Doppler cells decode to 0 or to one step, the
false detections (and the zero training cells) of the leakage rows.

With ``x̄`` the mean over the chirp axis ``c`` (``C`` chirps) and ``x̃ = x − x̄``,
every linear stage ``L`` before the Doppler DFT ``D`` (window, DFT, linear, sum along
other axes; windows along ``c``) splits exactly:

.. math:: D\,W\,L\,x = D\,W\,L\,\tilde x + (D\,W\,\tfrac{1}{C}\mathbf 1)\,(L\,\bar x)

where ``W`` is the Doppler window.  The pass rewrites the chain so that the spiking
stages compute the first term from the mean-removed samples (``<input>__moving``,
a ``linear`` along ``c`` with ``I − 𝟏𝟏ᵀ/C``), and the host computes the second,
exactly: the chirp mean (``<dop>__static_mean``, ``1 × C``), the other stages applied
to it (copies ``<dop>__static_<node>``: one range DFT per receiver and frame) and the
rank-one product with the Doppler weights' response to a constant
(``<dop>__static``, ``C_out × 1``: every Doppler bin — a symmetric Hann window leaks
to all of them).  An ``add`` node with the Doppler node's id sums the two, so every
consumer (magnitude, CFAR) reads the full spectrum; the spiking stages keep their ids
with ``__moving`` (their values are the moving part).

Applied (option ``static_split``, default ``auto``) to each ``dft`` along an axis
``c`` whose input is a chain of such linear stages from a graph input that has
``c``, with a ``dft``/``linear`` along another axis among them (the range DFT),
unless the option is ``off``, the Doppler DFT runs on the host, or a motif is chosen
for one of the chain's nodes by id.  Measured (loihi2, calibrated on other seeds,
seeds 0–4): seed003 cell sensitivity / precision 0.948 / 0.897 → 0.988 / 0.993,
carrada 0.976 / 0.994 → 0.993 / 0.995 (``docs/chip_accuracy.md``).

A chain with no Doppler DFT (a chirp sequence: range DFT, magnitude, CFAR per chirp)
repeats the same leakage over its chirps too: the last linear stage before a magnitude on
the host that leads to a CFAR is split along ``chirp`` the same way, its static part
being its value on the chirp mean, repeated (``<node>__static``, ``C × 1`` of ones);
measured on 16 chirps with leakage 40 dB over a weak target, loihi2, calibrated on other
frames: 176 → 274 of 275 cells kept (``tests/test_static_split.py``).

``records["static-split"]``: per split, the Doppler node, the input, the chirp axis
and the ids of the nodes added.

Examples
--------
>>> from compiler.chains import range_doppler_chain
>>> from compiler.passes.base import CompileContext
>>> from compiler.program import CompiledProgram
>>> from radar.config import preset
>>> p = StaticSplit().apply(CompileContext(), CompiledProgram(
...     graph=range_doppler_chain(preset("carrada"))))
>>> p.graph.op("dop").op_name(), p.graph.inputs_of("dop")
('add', ('dop__moving', 'dop__static'))
>>> p.records["static-split"][0]["moving_input"]
'adc__moving'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from pydantic import ConfigDict, Field

from compiler.lowering.dft_common import op_weights
from compiler.passes.base import CompileContext, Pass
from compiler.program import CompiledProgram
from ir import Graph
from ir.errors import CompileError, CompileValidationError
from ir.model import CheckedModel
from ir.ops import DFT, Add, Linear, Op, Sum, Window

__all__ = ["StaticSplit", "StaticSplitOptions", "MODES"]

#: The repetition axis a chain without a Doppler DFT is split along (the leakage and static
#: clutter repeat over chirps). Receivers are not: a broadside target's return is the same
#: on every channel too, so their mean is no static part.
REPETITION_AXIS = "chirp"

#: Values of the ``static_split`` option.
MODES = ("auto", "off")


class StaticSplitOptions(CheckedModel):
    """The pass's option, a typed field (``compile_graph(options={"static_split": ...})``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = CompileValidationError
    static_split: Literal["auto", "off"] = Field("auto", description="auto or off")

_LINEAR = (Window, DFT, Linear, Sum)


def _axis_of(op: Op) -> str:
    return op.axis


def _chain(graph: Graph, dop: str) -> tuple[str, list[str]] | None:
    """The graph input and the linear nodes from it to ``dop`` (excluded), or None."""
    axis, nodes, node = graph.op(dop).axis, [], dop
    while True:
        (src,) = graph.inputs_of(node)
        op = graph.op(src)
        if src in graph.input_ids():
            types = graph.infer_types()
            across = any(isinstance(graph.op(n), DFT | Linear) and _axis_of(graph.op(n)) != axis
                         for n in nodes)  # a transform along another axis comes first
            return (src, nodes[::-1]) if across and axis in types[src].axes else None
        if not isinstance(op, _LINEAR) or len(graph.consumers_of(src)) != 1:
            return None
        along = _axis_of(op) == axis
        if along and not isinstance(op, Window):  # only windows may act along the chirps
            return None
        nodes.append(src)
        node = src


def _linear(w: np.ndarray, axis: str, out_axis: str | None = None) -> Linear:
    imag = w.imag.tolist() if np.any(w.imag != 0) else None
    return Linear(axis=axis, out_axis=out_axis, matrix=w.real.tolist(), matrix_imag=imag)


def _chain_rep(graph: Graph, last: str, rep: str,
               motifs: dict[str, str]) -> tuple[str, list[str]] | None:
    """A chain of linear stages from a graph input with axis ``rep`` to ``last`` (included),
    none acting along ``rep``, ``last`` read only by magnitudes on the host that lead to a
    detector (a CFAR): or None."""
    consumers = graph.consumers_of(last)
    if _axis_of(graph.op(last)) == rep or not consumers:
        return None
    for c in consumers:
        op = graph.op(c)
        if op.op != "magnitude" or motifs.get(c, motifs.get(op.op, "host")) != "host":
            return None
        if not any(graph.op(d).op == "cfar" for d in _descendants(graph, c)):
            return None
    nodes, node = [], last
    while True:
        (src,) = graph.inputs_of(node)
        if src in graph.input_ids():
            ok = rep in graph.infer_types()[src].axes and graph.infer_types()[src].axes[rep] > 1
            return (src, nodes[::-1]) if ok else None
        op = graph.op(src)
        if (not isinstance(op, _LINEAR) or _axis_of(op) == rep
                or len(graph.consumers_of(src)) != 1):
            return None
        nodes.append(src)
        node = src


def _descendants(graph: Graph, node: str) -> set[str]:
    seen, stack = set(), [node]
    while stack:
        for c in graph.consumers_of(stack.pop()):
            if c not in seen:
                seen.add(c)
                stack.append(c)
    return seen


def _split(graph: Graph, dop: str, src: str, chain: list[str],
           rep: str | None = None) -> tuple[Graph, dict[str, Any]]:
    """Split the chain ``src → chain → dop``: along ``dop``'s own axis (the Doppler DFT) or,
    with ``rep``, along a repetition axis no stage acts on (``dop`` then is the last linear
    stage before a magnitude: the static part is its value on the mean, repeated)."""
    types = graph.infer_types()
    op_d = graph.op(dop)
    axis = rep or op_d.axis
    n = types[src].axes[axis]
    if rep is None:
        response = op_weights(op_d, n, node=dop).astype(np.complex128)  # (C_out, C)
    else:  # every repetition gets the same static value
        response = np.eye(n, dtype=np.complex128)
    for node in chain:  # the windows along the chirps act before D
        if _axis_of(graph.op(node)) == axis:
            response = response @ op_weights(graph.op(node), n, node=node)
    taken = set(graph)

    def fresh(name: str) -> str:
        if name in taken:
            raise CompileError(f"static-split: node id {name!r} exists already; rename it or "
                               "give the option static_split='off'", node=name)
        taken.add(name)
        return name

    moving_in = fresh(f"{src}__moving")
    renamed = {node: fresh(f"{node}__moving") for node in [*chain, dop]}
    mean_id = fresh(f"{dop}__static_mean")
    copies = {node: fresh(f"{dop}__static_{node}") for node in [*chain, *([dop] if rep else [])]
              if _axis_of(graph.op(node)) != axis}
    static_id = fresh(f"{dop}__static")
    out = Graph(graph.name)
    for node in graph:
        if node == dop:
            out.add(op_d, inputs=renamed[chain[-1]] if chain else moving_in, id=renamed[dop])
            continue
        if node in renamed:
            ins = [renamed.get(i, moving_in if i == src else i) for i in graph.inputs_of(node)]
            out.add(graph.op(node), inputs=ins, id=renamed[node])
            continue
        out.add(graph.op(node), inputs=graph.inputs_of(node), id=node)
        if node == src:
            out.add(_linear(np.eye(n) - 1.0 / n, axis), inputs=src, id=moving_in)
            out.add(_linear(np.full((1, n), 1.0 / n), axis), inputs=src, id=mean_id)
            prev = mean_id
            for orig, copy in copies.items():
                out.add(graph.op(orig), inputs=prev, id=copy)
                prev = copy
            out.add(_linear(response.sum(axis=1, keepdims=True), axis,
                            None if rep else op_d.out_axis), inputs=prev, id=static_id)
            out.add(Add(), inputs=[renamed[dop], static_id], id=dop)
    out.verify()
    record = {"dft": dop, "input": src, "axis": axis, "moving_input": moving_in,
              "moving": [renamed[k] for k in [*chain, dop]],
              "static": [mean_id, *copies.values(), static_id], "add": dop}
    return out, record


def host_nodes(record: list[dict[str, Any]]) -> list[str]:
    """The nodes a split added that must run on the host (all but the moving stages)."""
    return [n for r in record for n in (r["moving_input"], *r["static"], r["add"])]


@dataclass(frozen=True)
class StaticSplit(Pass):
    """Compute the part that repeats over chirps on the host; see the module docstring.

    Parameters
    ----------
    mode : {"auto", "off"}
        ``auto`` splits every chain that matches; ``off`` leaves the graph as it is.
    motifs : tuple of (str, str)
        The motifs the user chose (node id or op type → motif): a chain with a chosen
        motif on one of its stages, or a Doppler DFT on the host, is left as it is.
    """

    mode: Literal["auto", "off"] = "auto"
    motifs: tuple[tuple[str, str], ...] = ()
    name = "static-split"

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise CompileError(f"static_split={self.mode!r} is not a mode; use one of "
                               f"{', '.join(MODES)}")

    def apply(self, ctx: CompileContext, program: CompiledProgram) -> CompiledProgram:
        mode = self.mode
        record: list[dict[str, Any]] = []
        graph = program.graph
        motifs = dict(self.motifs)
        if mode == "auto":
            for dop in graph.topological_order():
                op = graph.op(dop)
                if not isinstance(op, DFT) or motifs.get(dop, motifs.get(op.op)) == "host":
                    continue
                found = _chain(graph, dop)
                if found is None or any(n in motifs for n in (*found[1], dop)):
                    continue
                graph, rec = _split(graph, dop, *found)
                record.append(rec)
            done = {n for r in record for n in (*r["moving"], *r["static"], r["add"])}
            for last in graph.topological_order():  # chirp sequences without a Doppler DFT
                op = graph.op(last)
                if (last in done or not isinstance(op, DFT | Linear)
                        or motifs.get(last, motifs.get(op.op)) == "host"):
                    continue
                found = _chain_rep(graph, last, REPETITION_AXIS, motifs)
                if found is None or any(n in motifs for n in (*found[1], last)):
                    continue
                graph, rec = _split(graph, last, *found, rep=REPETITION_AXIS)
                record.append(rec)
        program.graph = graph
        program.records.static_splits = record
        return program
