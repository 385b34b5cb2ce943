r"""Frame I/O figures (the top of Vogginger et al.'s Table 3): memory and bandwidth of a frame.

For a tensor of :math:`n` values of :math:`b` bits at :math:`f` frames/s:

.. math:: \text{memory} = n b / 8 \text{ bytes}, \qquad \text{bandwidth} = n b f \text{ bit/s},

reported in kB (:math:`10^3` bytes) and Mbit/s (:math:`10^6` bit/s).  The raw cube
is the graph's ``adc_input``; the RD map the first real node whose axes are
``range`` and ``doppler``; the RA map a real node with ``range`` and ``angle``, or,
when the chain has none, ``range`` bins × ``n_angle_bins`` (CARRADA's RA map has
256 angle bins).  Bits: ``real_bits`` per real value, ``2 × real_bits`` per
complex one (options).

Examples
--------
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "c", "nodes": [
...     {"id": "adc", "op": "adc_input", "shape": {"rx": 4, "chirp": 64, "sample": 256},
...      "complex": True},
...     {"id": "o", "op": "output", "input": "adc"}]})
>>> [(r["name"], r["memory_kB"], round(r["bandwidth_Mbit_s"], 2)) for r in frame_io(g)]
[('raw_cube', 262.144, 20.97)]
"""

from __future__ import annotations

from math import prod

from ir import Graph
from ir.types import TensorType

__all__ = ["frame_io", "io_figures"]


def io_figures(name: str, shape: dict[str, int], bits: int, frame_rate_hz: float,
               source: str) -> dict:
    """One frame-I/O row: values, bits per value, bytes, kB and Mbit/s.

    Examples
    --------
    >>> r = io_figures("rd_map", {"doppler": 64, "range": 256}, 16, 10.0, "node 'rd'")
    >>> r["memory_kB"], r["bandwidth_Mbit_s"]
    (32.768, 2.62144)
    """
    n = prod(shape.values())
    return {"name": name, "source": source, "shape": dict(shape), "values": n,
            "bits_per_value": bits, "bytes": n * bits / 8, "memory_kB": n * bits / 8 / 1e3,
            "bandwidth_Mbit_s": n * bits * frame_rate_hz / 1e6}


def _bits(t: TensorType, real_bits: int) -> int:
    return 2 * real_bits if t.complex else real_bits


def frame_io(graph: Graph, *, frame_rate_hz: float = 10.0, real_bits: int = 16,
             n_angle_bins: int | None = None) -> list[dict]:
    """The raw cube, RD map and RA map rows a chain has (see the module docstring).

    Parameters
    ----------
    graph : Graph
        A verified chain.
    frame_rate_hz : float
        Frames per second.
    real_bits : int
        Bits per real value (complex: twice).
    n_angle_bins : int, optional
        Angle bins of an RA map the chain does not compute (``None``: no RA row then).

    Returns
    -------
    list of dict
        Rows from :func:`io_figures`.
    """
    types = graph.infer_types()
    rows = []
    for nid in graph.topological_order():
        if graph.op(nid).op == "adc_input":
            rows.append(io_figures("raw_cube", types[nid].axes, _bits(types[nid], real_bits),
                                   frame_rate_hz, f"node {nid!r}"))
            break
    maps = {"rd_map": {"range", "doppler"}, "ra_map": {"range", "angle"}}
    for name, axes in maps.items():
        nid = next((n for n in graph.topological_order()
                    if set(types[n].names) == axes and not types[n].complex
                    and types[n].domain != "mask"), None)
        if nid is not None:
            rows.append(io_figures(name, types[nid].axes, real_bits, frame_rate_hz,
                                   f"node {nid!r}"))
        elif name == "ra_map" and n_angle_bins:
            rng = next((types[n].axes["range"] for n in graph.topological_order()
                        if "range" in types[n].axes), None)
            if rng is not None:
                rows.append(io_figures(name, {"range": rng, "angle": n_angle_bins}, real_bits,
                                       frame_rate_hz, f"range bins x n_angle_bins={n_angle_bins}"))
    return rows
