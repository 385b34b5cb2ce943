r"""The per-stage accuracy contract: what a spiking stage must keep, measured on held-back frames.

Every value a spiking segment decodes (a DFT, a magnitude, a power map) and every
decision it takes (a CFAR) is compared with the conventional chain's value on the
same frames — frames the calibration did not see (:func:`split_folds`) — with the
figures of :mod:`compiler.accuracy.metrics`. A stage *holds* when all its figures are
within the :class:`Tolerances`:

===================  ==========================================================  =========
figure               meaning                                                     default
===================  ==========================================================  =========
``error_db``         RMS error over the noise cells relative to the noise floor  ≤ −10 dB
``lost``             fraction of signal cells (12 dB over the floor) > 6 dB off  ≤ 1 %
``clipped``          fraction of a value stage's encoded inputs clipped          ≤ 10⁻⁴
``sensitivity``      detected cells kept, against the conventional mask          ≥ 0.97
``precision``        spiking detections that the conventional chain also has     ≥ 0.97
``missed``           conventional objects with no spiking detection within ±1    0
``extra_per_map``  spiking objects with no conventional detection within ±1    ≤ 1
``overflow``         neuron-steps whose state left the chip's ``state_bits``     0
===================  ==========================================================  =========

A −10 dB error moves a CFAR's noise estimate by under 0.5 dB; a code that decodes the
noise to 0 scores 0 dB. A detector's clipped inputs are reported, not judged by
themselves: a return above the top of its latency code (leakage) fires first either way,
and what clipping costs shows in the decisions and objects. Errors of upstream stages
carry into later ones, as on the chip, so the *first* stage that breaks its contract (in
program order) is the one named.

The reference simulator computes wider than a chip's state: where a membrane or current
of a stage's populations leaves ``±(2^(state_bits−1) − 1)`` the chip's ``u`` wraps and its
``v`` saturates (and fires), so what was simulated is not what the chip computes. Those
neuron-steps (``SimResult.state_overflow``; the closed form counts the final membranes, a
lower bound) break the contract of the stage whose populations they are, whatever its
other figures.

Examples
--------
>>> t = Tolerances()
>>> t.error_db_max, t.sensitivity_min, t.extra_per_map_max
(-10.0, 0.97, 1.0)
>>> s = StageCheck(node="det", motif="time", kind="decisions",
...                figures={"sensitivity": 0.9, "precision": 1.0, "missed": 2,
...                         "extra_per_map": 0.0, "objects": 12},
...                clipped=0.0)
>>> s.failures(t)
['sensitivity 0.900 < 0.97', 'missed 2 of 12 objects > 0']
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import ConfigDict, Field

from compiler.accuracy.metrics import FIRM_MARGIN_DB, decision_figures, value_figures
from ir import Graph
from ir.errors import CompileValidationError
from ir.interpreter import evaluate
from ir.model import CheckedModel
from ir.ops import Input, Output

__all__ = ["Contract", "StageCheck", "Tolerances", "firm_detections", "measure_contract",
           "split_folds"]


class Tolerances(CheckedModel):
    """What every spiking stage must keep (see the module docstring for each figure)."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = CompileValidationError
    error_db_max: float = Field(-10.0, le=0, description="RMS error over the noise cells, dB "
                                                         "relative to the noise floor")
    lost_max: float = Field(0.01, ge=0, le=1, description="fraction of signal cells > 6 dB off")
    clipped_max: float = Field(1e-4, ge=0, le=1, description="fraction of inputs clipped")
    sensitivity_min: float = Field(0.97, ge=0, le=1, description="cell sensitivity")
    precision_min: float = Field(0.97, ge=0, le=1, description="cell precision")
    missed_max: int = Field(0, ge=0, description="conventional objects lost")
    extra_per_map_max: float = Field(1.0, ge=0, description="extra objects per map")


@dataclass(frozen=True)
class StageCheck:
    """One decoded node of a spiking segment against the conventional chain."""

    node: str
    motif: str
    kind: str
    figures: dict[str, Any]
    clipped: float = 0.0
    upstream: tuple[str, ...] = ()
    overflow: int = 0

    def failures(self, tol: Tolerances) -> list[str]:
        """One phrase per figure beyond its tolerance (empty: the stage holds)."""
        f, out = self.figures, []
        if self.overflow:
            out.append(f"{self.overflow} neuron-steps beyond the chip's state range "
                       "(its u wraps, its v saturates: the simulation is not the chip)")
        if self.kind == "values":  # a detector's clipped inputs show in its decisions
            if self.clipped > tol.clipped_max:
                out.append(f"clipped {self.clipped:.2e} of its inputs > {tol.clipped_max:g}")
            if f["error_db"] > tol.error_db_max:
                out.append(f"error {f['error_db']:+.1f} dB re noise > {tol.error_db_max:g} dB")
            if f["lost"] > tol.lost_max:
                out.append(f"lost {100 * f['lost']:.1f} % of signal cells > "
                           f"{100 * tol.lost_max:g} %")
            return out
        if f["sensitivity"] < tol.sensitivity_min:
            out.append(f"sensitivity {f['sensitivity']:.3f} < {tol.sensitivity_min:g}")
        if f["precision"] < tol.precision_min:
            out.append(f"precision {f['precision']:.3f} < {tol.precision_min:g}")
        if f["missed"] > tol.missed_max:
            out.append(f"missed {f['missed']} of {f['objects']} objects > {tol.missed_max}")
        if f["extra_per_map"] > tol.extra_per_map_max:
            out.append(f"{f['extra_per_map']:.1f} extra objects per map > "
                       f"{tol.extra_per_map_max:g}")
        return out

    def describe(self) -> str:
        """One line: the stage, its motif and its headline figures."""
        f = self.figures
        via = f" (via {' → '.join(self.upstream)})" if self.upstream else ""
        if self.kind == "values":
            body = (f"error {f['error_db']:+.1f} dB re noise, lost {100 * f['lost']:.2f} % "
                    f"of {f['signal_cells']} signal cells")
        else:
            body = (f"sensitivity {f['sensitivity']:.3f}, precision {f['precision']:.3f}, "
                    f"objects kept {f['kept']}/{f['objects']}, "
                    f"{f['extra_per_map']:.2f} extra per map")
        over = f", {self.overflow} states out of range" if self.overflow else ""
        return f"{self.node} [{self.motif}]{via}: {body}, clipped {self.clipped:.1e}{over}"

    def to_dict(self) -> dict:
        """JSON-able."""
        return {"node": self.node, "motif": self.motif, "kind": self.kind,
                "figures": self.figures, "clipped": self.clipped,
                "upstream": list(self.upstream), "overflow": self.overflow}


@dataclass(frozen=True)
class Contract:
    """:func:`measure_contract`'s result: every stage, in program order, and the folds used."""

    stages: list[StageCheck] = field(default_factory=list)
    tolerances: Tolerances = field(default_factory=Tolerances)
    n_frames: int = 0
    held_out: bool = True
    note: str = ""

    def failing(self) -> list[tuple[StageCheck, list[str]]]:
        """The stages that break the contract, with their failures, in program order."""
        return [(s, f) for s in self.stages if (f := s.failures(self.tolerances))]

    @property
    def holds(self) -> bool:
        """Whether every stage is within its tolerances."""
        return not self.failing()

    def lines(self) -> list[str]:
        """A summary, one line per stage, marked ``ok`` or ``FAILS``."""
        head = (f"accuracy on {self.n_frames} "
                f"{'held-out' if self.held_out else 'calibration (not held-out)'} frame(s)"
                + (f"; {self.note}" if self.note else ""))
        out = [head]
        for s in self.stages:
            f = s.failures(self.tolerances)
            out.append(f"  {'FAILS' if f else 'ok   '} {s.describe()}"
                       + (f" — {'; '.join(f)}" if f else ""))
        return out

    def to_dict(self) -> dict:
        """JSON-able: tolerances, frames, stages and whether the contract holds."""
        return {"holds": self.holds, "n_frames": self.n_frames, "held_out": self.held_out,
                "note": self.note, "tolerances": self.tolerances.model_dump(),
                "stages": [{**s.to_dict(), "failures": s.failures(self.tolerances)}
                           for s in self.stages]}


def split_folds(inputs: Mapping[str, np.ndarray], n_frames: int | None
                ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray] | None]:
    """Calibration inputs with a frames axis → (fit fold, check fold).

    The last third of the frames (at least one) is held back for the check; with one
    frame (or no frames axis) there is nothing to hold back: ``(inputs, None)``.

    Examples
    --------
    >>> fit, check = split_folds({"x": np.arange(6).reshape(3, 2)}, 3)
    >>> fit["x"].tolist(), check["x"].tolist()
    ([[0, 1], [2, 3]], [[4, 5]])
    >>> split_folds({"x": np.zeros(4)}, None)[1] is None
    True
    """
    if not n_frames or n_frames < 2:
        return dict(inputs), None
    k = max(1, n_frames // 3)
    fit = {n: np.asarray(v)[: n_frames - k] for n, v in inputs.items()}
    check = {n: np.asarray(v)[n_frames - k:] for n, v in inputs.items()}
    return fit, check


def _axes_of(graph, node: str, frames: bool) -> tuple[int, ...]:
    op = graph.op(node)
    (src,) = graph.inputs_of(node)[:1] or (node,)
    names = list(graph.infer_types()[src].axes)
    axes = getattr(op, "axes", None) or names
    return tuple(names.index(a) + int(frames) for a in axes)


def measure_contract(program, values: Mapping[str, np.ndarray],
                     reference: Mapping[str, np.ndarray], clipped: Mapping[str, int], *,
                     n_frames: int, framed: bool | None = None,
                     tolerances: Tolerances | None = None, held_out: bool = True,
                     note: str = "", overflow: Mapping[str, int] | None = None) -> Contract:
    """Every decoded node of every spiking segment against the golden values.

    Parameters
    ----------
    program : CompiledProgram
        The compiled chain.
    values, reference : mapping of str to ndarray
        The simulator's and the reference interpreter's value of every node on the
        check frames.
    clipped : mapping of str to int
        Values clipped per encoder port (an IR node id) on those frames.
    n_frames : int
        Frames checked.
    framed : bool, optional
        Whether the arrays carry a leading frames axis (default: ``n_frames > 1``; a
        single check frame cut from a stack keeps its axis of length 1).
    tolerances : Tolerances, optional
        The contract (default :class:`Tolerances`).
    held_out, note : bool, str
        Whether the frames were held back from the calibration, and a remark.
    overflow : mapping of str to int, optional
        Per population id, neuron-steps beyond the chip's state range on those frames
        (``SimResult.state_overflow``); each stage carries those of its segment's
        populations built for it or for the nodes inside the segment before it.

    Returns
    -------
    Contract
    """
    tol = tolerances or Tolerances()
    graph = program.graph
    motifs = dict(program.records.motifs)
    framed = n_frames > 1 if framed is None else bool(framed)
    stages = []
    for seg in program.segments:
        if seg.kind != "spiking":
            continue
        sizes = [int(np.asarray(reference[i]).size) for i in seg.inputs if i in reference]
        n_clip = sum(int(clipped.get(i, 0)) for i in seg.inputs)
        frac = n_clip / max(sum(sizes), 1)
        inner = tuple(n for n in graph.topological_order()
                      if motifs.get(n, "host") != "host" and n not in seg.outputs
                      and n in _segment_nodes(program, seg))
        over_of = _overflow_by_node(seg.network, overflow or {})
        for node in seg.outputs:
            if node not in values or node not in reference:
                continue
            got, want = np.asarray(values[node]), np.asarray(reference[node])
            if want.dtype == bool:
                src = graph.inputs_of(node)[0]
                fig = decision_figures(got, want, np.asarray(reference[src]),
                                       axes=_axes_of(graph, node, framed), frames=n_frames,
                                       firm=firm_detections(graph, node, reference[src],
                                                            program.evaluators)).to_dict()
                kind = "decisions"
            else:
                fig = value_figures(got, want).to_dict()
                kind = "values"
            stages.append(StageCheck(node=node, motif=str(motifs.get(node, "?")), kind=kind,
                                     figures=fig, clipped=frac, upstream=inner,
                                     overflow=sum(over_of.get(n, 0) for n in (node, *inner, ""))))
    return Contract(stages=stages, tolerances=tol, n_frames=n_frames, held_out=held_out,
                    note=note)


def firm_detections(graph, node: str, x: np.ndarray, evaluators=None) -> np.ndarray | None:
    """The conventional detections of CFAR ``node`` on its input ``x`` that hold with its
    threshold :data:`~compiler.accuracy.metrics.FIRM_MARGIN_DB` higher (None: not a CFAR
    on power or amplitude): the cells any faithful code must keep."""
    op = graph.op(node)
    if not hasattr(op, "alpha_for"):
        return None
    types = graph.infer_types()
    (src,) = graph.inputs_of(node)
    t = types[src]
    if t.domain not in ("power", "amplitude"):
        return None
    db = FIRM_MARGIN_DB / (10 if t.domain == "power" else 20)
    alpha = op.alpha_for(op.window(node, t).n_train) * 10 ** db
    raised = op.model_copy(update={"alpha": alpha, "pfa": None})
    g = Graph(f"{graph.name}-firm")
    g.add(Output(), g.add(raised, g.add(Input(shape=dict(t.axes), complex=t.complex,
                                              domain=t.domain), id="x"), id="c"), id="o")
    return np.asarray(evaluate(g, {"x": np.asarray(x)}, registry=evaluators)["o"], bool)


def _overflow_by_node(network, overflow: Mapping[str, int]) -> dict[str, int]:
    """Neuron-steps out of the state range per IR node (a population's ``origin``) of
    ``network``; populations without an origin count towards every stage of the segment.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> net = NS(populations=[NS(id="f/a", origin={"node": "f"}), NS(id="r", origin={})])
    >>> _overflow_by_node(net, {"f/a": 3, "r": 2, "other": 9})
    {'f': 3, '': 2}
    """
    out: dict[str, int] = {}
    for pop in getattr(network, "populations", None) or ():
        n = int(overflow.get(pop.id, 0))
        if n:
            key = pop.origin.get("node", "")
            out[key] = out.get(key, 0) + n
    return out


def _segment_nodes(program, seg) -> set[str]:
    """IR nodes computed inside a spiking segment (between its inputs and its outputs)."""
    graph = program.graph
    inside: set[str] = set()
    stack = list(seg.outputs)
    while stack:
        n = stack.pop()
        if n in inside or n in seg.inputs:
            continue
        inside.add(n)
        stack.extend(graph.inputs_of(n))
    return inside
