r"""Segment boundaries of a compiled program and their bandwidth (host ↔ spiking traffic).

A :class:`~compiler.program.CompiledProgram` runs spiking and host segments that
exchange IR values by node id.  Every value that crosses between the chip and the
host is one row:

``spiking→host``
    a value decoded from a spiking segment and read by host segments (one row
    per value, however many host segments read it: it leaves the chip once);
``host→spiking``
    a host value (a graph input or a host segment's result) encoded into a
    spiking segment (one row per reading spiking segment);
``spiking→spiking via host``
    a value decoded from one spiking segment and encoded into another (one row
    per reading segment; it crosses the chip boundary twice, out and back in).

Host→host values never leave the host and are not listed.  For a value of type
:math:`T` with :math:`n` values per frame and :math:`b` bits per value, at
:math:`f` frames/s:

.. math:: \text{bits/frame} = c\, n b, \qquad \text{kB/frame} = c\, n b / 8000, \qquad
          \text{Mbit/s} = c\, n b f / 10^6,

with :math:`c` = ``crossings`` (2 for a via-host row, else 1).  :math:`b` is
``real_bits`` for a real value, twice that for a complex one and 1 for a mask (a
spike per detection).  When the value has the ``frame_axis`` (a chain processing
several radar frames per run), :math:`n` is its size divided by that axis's size,
so the figures stay per radar frame.

Examples
--------
>>> from ir import Graph
>>> from compiler.program import CompiledProgram, Segment
>>> g = Graph.from_dict({"name": "c", "nodes": [
...     {"id": "x", "op": "input", "shape": {"frame": 2, "range": 8}, "domain": "power"},
...     {"id": "det", "op": "threshold", "input": "x", "value": 1.0},
...     {"id": "o", "op": "output", "input": "det"}]})
>>> p = CompiledProgram(graph=g, segments=[
...     Segment("spiking", inputs=["x"], outputs=["det"]),
...     Segment("host", inputs=["det"], outputs=["o"], node="o")])
>>> [(r["kind"], r["node"], r["values_per_frame"], r["bits_per_value"], r["Mbit_s"])
...  for r in boundary_rows(p, frame_rate_hz=10.0, real_bits=16)]
[('host→spiking', 'x', 8, 16, 0.00128), ('spiking→host', 'det', 8, 1, 8e-05)]
"""

from __future__ import annotations

from ir.types import TensorType

__all__ = ["boundary_rows", "segment_names"]


def segment_names(program) -> list[str]:
    """Display name of each segment: its network's name (spiking) or ``host:<node>``.

    Examples
    --------
    >>> from ir import Graph
    >>> from compiler.program import CompiledProgram, Segment
    >>> g = Graph.from_dict({"nodes": [{"id": "a", "op": "input", "shape": {"r": 2}},
    ...                                {"id": "o", "op": "output", "input": "a"}]})
    >>> segment_names(CompiledProgram(g, [Segment("host", ["a"], ["o"], node="o")]))
    ['host:o']
    """
    names = []
    for k, seg in enumerate(program.segments):
        if seg.kind == "host":
            names.append(f"host:{seg.node}")
        else:
            net = getattr(seg.network, "name", None)
            names.append(net or f"spiking#{k}")
    return names


def _bits(t: TensorType, real_bits: int) -> int:
    if t.domain == "mask":
        return 1
    return 2 * real_bits if t.complex else real_bits


def boundary_rows(program, frame_rate_hz: float, real_bits: int = 16, *,
                  frame_axis: str = "frame") -> list[dict]:
    """One row per value crossing between host and spiking segments (module docstring).

    Parameters
    ----------
    program : CompiledProgram
        Its ``graph`` and ``segments`` (in execution order).
    frame_rate_hz : float
        Radar frames per second :math:`f`.
    real_bits : int
        Bits per real value (complex: twice; masks: 1).
    frame_axis : str
        An axis counting radar frames within one run (figures are divided by its size).

    Returns
    -------
    list of dict
        Keys ``kind, from, to, node, shape, values_per_frame, bits_per_value,
        crossings, bits_per_frame, kB_per_frame, Mbit_s``, in execution order of the
        producing segment.
    """
    types = program.graph.infer_types()
    names = segment_names(program)
    producer = {}
    for k, seg in enumerate(program.segments):
        for node in seg.outputs:
            producer[node] = k
    readers: dict[str, list[int]] = {}
    for k, seg in enumerate(program.segments):
        for node in dict.fromkeys(seg.inputs):
            if producer.get(node) != k:
                readers.setdefault(node, []).append(k)
    rows = []

    def row(kind: str, node: str, src: str, dst: str, crossings: int) -> None:
        t = types[node]
        n = t.size // t.axes.get(frame_axis, 1)
        bits = _bits(t, real_bits)
        rows.append({"kind": kind, "from": src, "to": dst, "node": node, "shape": dict(t.axes),
                     "values_per_frame": n, "bits_per_value": bits, "crossings": crossings,
                     "bits_per_frame": crossings * n * bits,
                     "kB_per_frame": crossings * n * bits / 8e3,
                     "Mbit_s": crossings * n * bits * frame_rate_hz / 1e6})

    order = sorted(readers, key=lambda v: (producer.get(v, -1), list(types).index(v)))
    for node in order:
        src = producer.get(node)
        from_spikes = src is not None and program.segments[src].kind == "spiking"
        src_name = names[src] if src is not None else "input"
        to_host = [names[k] for k in readers[node] if program.segments[k].kind == "host"]
        to_spikes = [k for k in readers[node] if program.segments[k].kind == "spiking"]
        if from_spikes and to_host:
            row("spiking→host", node, src_name, ", ".join(to_host), 1)
        for k in to_spikes:
            if from_spikes:
                row("spiking→spiking via host", node, src_name, names[k], 2)
            else:
                row("host→spiking", node, src_name, names[k], 1)
    return rows
