r"""Physical units under the ``per-input`` calibration policy.

Under ``per-input`` the chain is calibrated on graph inputs normalised per slice —
each slice over the axes a later stage mixes divided by its largest part ``p``
(:func:`compiler.snn.coding.normalize_values`) — so every downstream value is in
those normalised units.  :func:`run_program <backends.reference.program.run_program>`
normalises such inputs on the host first (the encoders' own normalisation is then
the identity), runs the segments as calibrated, and turns each value back into the
units of its input with the degree its domain has in the input's amplitude:

=============  =============================================
domain         physical value
=============  =============================================
``amplitude``  :math:`y \cdot p`  (window, DFT, sum, \|x\|, …)
``power``      :math:`y \cdot p^2`
``db``         :math:`y + 20 \log_{10} p`
``mask``       :math:`y` (a decision does not scale)
=============  =============================================

``p`` broadcasts over the node's axes by name (the input's axes that are not
normalised, kept in the node).  A node that depends on more than one normalised
input, or has lost one of those axes, stays in normalised units and is listed in
:attr:`~backends.reference.program.ProgramResult.normalized`.

Examples
--------
>>> import numpy as np
>>> from backends.reference import run_program
>>> from compiler.compile import compile_graph
>>> from ir import DFT, Graph, Input, Output
>>> g = Graph(name="x")
>>> _ = g.add(Output(), g.add(DFT(axis="sample", keep="positive"),
...                           g.add(Input(shape={"chirp": 2, "sample": 8}), id="a")))
>>> x = np.cos(np.arange(8) * np.pi / 2)[None] * np.array([[1.0], [100.0]])
>>> p = compile_graph(g, calibration="per-input", calibration_inputs={"a": x})
>>> np.abs(run_program(p, {"a": x}).outputs[g.output_ids()[0]]).max(axis=1).round(1).tolist()
[4.0, 400.0]
"""

from __future__ import annotations

from collections.abc import Mapping

import networkx as nx
import numpy as np

from compiler.passes.calibrate import mixed_axes
from compiler.program import CompiledProgram
from compiler.snn.coding import normalize_values

__all__ = ["apply_units", "normalize_inputs", "normalized_inputs", "unit_plan"]


def normalized_inputs(program: CompiledProgram) -> dict[str, tuple[str, ...]]:
    """``{graph input: normalised axes}`` under the ``per-input`` policy.

    From the program's options (``calibration``, kept in artifacts): every graph input over
    the axes a later stage mixes (:func:`compiler.passes.calibrate.mixed_axes`), as the
    calibrate pass normalised it — also where the encoded value is computed from the input
    on the host first (the static split's mean-removed samples); plus the encoders that
    normalise a graph input themselves (a network compiled on its own).

    Examples
    --------
    >>> from compiler.program import CompiledProgram
    >>> from ir import Graph
    >>> normalized_inputs(CompiledProgram(graph=Graph(name="g")))
    {}
    """
    inputs = set(program.graph.input_ids())
    out = {e.port: tuple(e.normalize_axes) for net in program.networks for e in net.encoders
           if e.port in inputs and e.normalize_axes}
    if program.calibration_policy == "per-input":
        for node in program.graph.input_ids():
            axes = mixed_axes(program.graph, node)
            if axes:
                out.setdefault(node, axes)
    return out


def normalize_inputs(values: Mapping[str, np.ndarray], axes: Mapping[str, tuple[str, ...]],
                     names: Mapping[str, tuple[str, ...]]
                     ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Inputs divided per slice by their peak part, and the peaks (keepdims, zeros as 1)."""
    out, peaks = dict(values), {}
    for node, ax in axes.items():
        x = np.asarray(values[node])
        idx = tuple(names[node].index(a) for a in ax)
        peak = np.maximum(np.abs(np.real(x)), np.abs(np.imag(x))).max(axis=idx, keepdims=True)
        peaks[node] = np.where(peak > 0, peak, 1.0)
        out[node] = normalize_values(x, idx)
    return out, peaks


def unit_plan(program: CompiledProgram, types: Mapping, nodes: list[str] | None = None
              ) -> tuple[dict[str, tuple], list[str]]:
    """How each of ``nodes`` (default: all) returns to its input's units, and those that stay.

    A step is ``(input, domain, kept_shape, perm, shape)``: the input's peak reshaped to
    its kept axes (``kept_shape``, input order), transposed by ``perm`` into the node's
    order and reshaped to ``shape`` (1 on the node's other axes) — plain tuples, so a
    generated package applies the same plan (:func:`apply_units`).
    """
    axes = normalized_inputs(program)
    if not axes:
        return {}, []
    graph = program.graph.to_networkx()
    plan, left = {}, []
    for node in nodes if nodes is not None else list(graph.nodes):
        domain = types[node].domain
        sources = ({node} | nx.ancestors(graph, node)) & set(axes)
        if domain == "mask" or not sources:
            continue
        if len(sources) > 1:
            left.append(node)
            continue
        (src,) = sources
        src_names, dst = types[src].names, types[node].names
        kept = [a for a in src_names if a not in axes[src]]
        if any(a not in dst for a in kept):
            left.append(node)
            continue
        order = sorted(kept, key=dst.index)
        plan[node] = (src, domain, tuple(types[src].axes[a] for a in kept),
                      tuple(kept.index(a) for a in order),
                      tuple(types[node].axes[a] if a in kept else 1 for a in dst))
    return plan, sorted(left)


def apply_units(values: Mapping[str, np.ndarray], peaks: Mapping[str, np.ndarray],
                plan: Mapping[str, tuple]) -> dict[str, np.ndarray]:
    """``values`` with each planned node in its input's units (the module's table)."""
    out = dict(values)
    for node, (src, domain, kept_shape, perm, shape) in plan.items():
        p = np.reshape(np.transpose(np.reshape(peaks[src], kept_shape), perm), shape)
        if domain == "amplitude":
            out[node] = values[node] * p
        elif domain == "power":
            out[node] = values[node] * (p * p)
        else:  # db
            out[node] = values[node] + 20.0 * np.log10(p)
    return out
