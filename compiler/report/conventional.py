r"""The same chain on a radar DSP: cycles, seconds and joules per frame from cited figures.

The conventional cost of a stage is what the C674x DSP of TI's single-chip radars spends
on the IR node the stage computes: an :math:`N`-point DFT as TI's ``DSP_fft16x16``, whose
published cycle count is

.. math:: c_\mathrm{FFT}(N) = (6 N / 8 + 19)\,\lceil \log_4 N - 1 \rceil + N + 30

(:math:`N` zero-padded to a power of two, at least 16), times the transforms of the
node; a CFAR as the conventional row of Table 1 (:mod:`compiler.report.opcounts`) per
cell; a window, magnitude, sum, threshold or dense linear map as one operation per value
(per multiply-accumulate). Cycles :math:`c` give :math:`t = c / f` and
:math:`E = c \cdot e_\mathrm{cycle}`; every constant is a :class:`~compiler.hardware.
figures.Figure` in :data:`DSP` with its source. Ops without a rule (a classifier, a
clusterer) have no conventional figure.

Examples
--------
>>> fft_cycles(256)  # (6*32 + 19) * 3 + 256 + 30
919
>>> fft_cycles(4)  # padded to 16 points: (12 + 19) * 1 + 16 + 30
77
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "r", "nodes": [
...     {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 256}},
...     {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> row = conventional_rows(g, ["f"])[0]
>>> row["cycles"], round(row["energy_J"] * 1e6, 3)  # 2 x 919 cycles x 1.4231 nJ, in uJ
(1838, 2.616)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from math import ceil, log

from compiler.hardware.figures import Figure
from compiler.report.opcounts import cfar_op_counts
from ir import Graph

__all__ = ["DSP", "RULES", "conventional_rows", "fft_cycles"]

#: The DSP's constants, each with its source.
DSP: dict[str, Figure] = {
    "clock_hz": Figure(value=600e6, source=(
        "TI, 'AWR1642 mmWave sensor: 76-81-GHz radar-on-chip for short-range radar "
        "applications' (white paper, Singh et al. 2017): a 600-MHz C674x DSP (the DSP of the "
        "AWR16xx/AWR18xx)")),
    "energy_per_cycle_j": Figure(value=1.4231e-9, source=(
        "derived: TI SPRABF9 (C6748/46/42 power consumption summary, 2019): a C674x device's "
        "typical total power 426.93 mW at 300 MHz, 1.2 V core, 25 C / 300 MHz; assumption: "
        "the radar's C674x at 600 MHz spends the same per cycle")),
    "fft_cycles": Figure(value=None, source=(
        "TI SPRUEB8 (TMS320C64x+ DSPLIB Programmer's Reference, 2006), DSP_fft16x16 "
        "benchmark: (6 N/8 + 19) ceil(log4 N - 1) + N + 30 cycles (the C674x runs C64x+ "
        "code); assumption: N zero-padded to a power of two >= 16")),
    "cycles_per_op": Figure(value=1.0, source=(
        "assumption: one cycle per CFAR ADD/CMP of Table 1, per window multiply, "
        "magnitude, sum term or linear multiply-accumulate (no SIMD): an upper bound on the "
        "DSP's cycles")),
}


def fft_cycles(n: int) -> int:
    """Cycles of one ``DSP_fft16x16`` of ``n`` points (padded to a power of two >= 16)."""
    n = max(16, 1 << max(0, ceil(log(n, 2) - 1e-9)))
    stages = ceil(log(n, 4) - 1 - 1e-9)
    return (6 * n // 8 + 19) * stages + n + 30


def _dft(op, t_in, t_out) -> float:
    size = t_in.axes[op.axis]
    ops = t_in.size if op.window is not None else 0  # a folded window: one multiply a value
    return (t_in.size // size) * fft_cycles(op.n_points(size)) + ops * DSP["cycles_per_op"].value


def _cfar(op, t_in, t_out) -> float:
    n_train = op.window("", t_in).n_train
    per_cell = cfar_op_counts(op.kind, n_train, 0)[0]["total"]
    return t_out.size * per_cell * DSP["cycles_per_op"].value


def _per_output(op, t_in, t_out) -> float:
    return t_out.size * DSP["cycles_per_op"].value


def _per_input(op, t_in, t_out) -> float:
    return t_in.size * DSP["cycles_per_op"].value


def _linear(op, t_in, t_out) -> float:
    return t_out.size * op.n_in * DSP["cycles_per_op"].value


#: Op name -> cycles(op, input type, output type) on the DSP.
RULES: dict[str, Callable] = {"dft": _dft, "cfar": _cfar, "window": _per_output,
                              "magnitude": _per_output, "threshold": _per_output,
                              "log": _per_output, "add": _per_output, "sum": _per_input,
                              "linear": _linear}


def conventional_rows(graph: Graph, nodes: Sequence[str],
                      rules: Mapping[str, Callable] = RULES) -> list[dict]:
    """The DSP's cycles, seconds and joules per frame for each of ``nodes`` of ``graph``.

    Parameters
    ----------
    graph : Graph
        The program's graph (after the compiler's rewrites).
    nodes : sequence of str
        The nodes the spiking stages compute (a node not in ``graph`` gets no figure).
    rules : mapping
        Op name -> cycles function (default :data:`RULES`).

    Returns
    -------
    list of dict
        ``node``, ``op``, ``cycles``, ``latency_s``, ``energy_J`` (``None`` where no rule).
    """
    types = graph.infer_types()
    rows = []
    for nid in nodes:
        op = graph.op(nid) if nid in graph else None
        rule = rules.get(op.op) if op is not None else None
        if rule is None:
            rows.append({"node": nid, "op": op.op if op else None, "cycles": None,
                         "latency_s": None, "energy_J": None})
            continue
        inputs = graph.inputs_of(nid)
        cycles = rule(op, types[inputs[0]], types[nid])
        cycles = int(cycles) if float(cycles).is_integer() else cycles
        rows.append({"node": nid, "op": op.op, "cycles": cycles,
                     "latency_s": cycles / DSP["clock_hz"].value,
                     "energy_J": cycles * DSP["energy_per_cycle_j"].value})
    return rows
