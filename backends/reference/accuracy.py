r"""How far a compiled program's spiking segments are from the conventional chain, measured.

A motif can compile, fit and still be the wrong choice: the radix-4 S-FFT
(``time-fft``) on the TI chirps keeps about 9 % RMS error, enough for an OS-CFAR
behind it to report 51 detections where the conventional chain reports 6.
:func:`check_accuracy` runs the program on sample frames (the calibration data, as
``radarsnn compile`` does) and the reference interpreter on the same frames, and
compares every value a spiking segment decodes:

``values`` (a DFT, a magnitude …)
    relative RMS error :math:`e = \lVert \hat y - y\rVert_2 / \lVert y\rVert_2` over all
    cells of all frames; *large* when :math:`e >` :data:`VALUE_RTOL` (5 %).  The
    default time-coded S-FT keeps 0.5–2 % on the TI chirps, the rate-coded DFT 1–3 %.
``decisions`` (a CFAR, a threshold: masks)
    the cells where the spiking decision differs, against the conventional count of
    detections :math:`n`; *large* when more than :math:`\max(2, n/4)` cells differ.

The reference for a node is the interpreter's value on the program's own graph
(after the compiler's rewrites), so a segment is judged on exactly what it was
compiled to compute; errors of upstream spiking segments carry into it, as they do
on the chip.

Examples
--------
>>> import numpy as np
>>> from compiler.compile import compile_graph
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "r", "nodes": [
...     {"id": "x", "op": "input", "shape": {"sample": 16}},
...     {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "range"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> x = np.random.default_rng(0).normal(size=(2, 16))
>>> check = check_accuracy(compile_graph(g, None, calibration_inputs={"x": x}), {"x": x})
>>> [(a.node, a.kind, a.large) for a in check.nodes], check.warnings()
([('f', 'values', False)], [])
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from backends.reference.program import run_program
from compiler.program import CompiledProgram
from ir.errors import RadarSNNError, SimulationError
from ir.frames import n_frames
from ir.interpreter import evaluate
from ir.model import short_repr

__all__ = ["VALUE_RTOL", "AccuracyCheck", "NodeAccuracy", "check_accuracy"]

#: Relative RMS error above which a decoded value is reported as large.
VALUE_RTOL = 0.05


@dataclass(frozen=True)
class NodeAccuracy:
    """One decoded node against the conventional chain, over the checked frames.

    Attributes
    ----------
    node, motif : str
        The IR node and the motif it was lowered with (``"?"`` when not recorded).
    kind : {"values", "decisions"}
        A numeric value (relative RMS error) or a mask (differing cells).
    error : float
        Relative RMS error, or the fraction of cells whose decision differs.
    differing, spiking, conventional : int
        For decisions: cells that differ, detections of the spiking and of the
        conventional chain (0 for values).
    """

    node: str
    motif: str
    kind: str
    error: float
    differing: int = 0
    spiking: int = 0
    conventional: int = 0

    @property
    def large(self) -> bool:
        """Whether the figure is beyond the module's bound (:data:`VALUE_RTOL`, or the counts)."""
        if self.kind == "values":
            return self.error > VALUE_RTOL
        return self.differing > max(2, self.conventional / 4)

    def describe(self) -> str:
        """One sentence with the figure."""
        head = f"node {self.node!r} (motif {self.motif})"
        if self.kind == "values":
            return f"{head}: {100 * self.error:.1f} % RMS error against the conventional value"
        return (f"{head}: {self.spiking} detections where the conventional chain has "
                f"{self.conventional} ({self.differing} cells differ)")


@dataclass(frozen=True)
class AccuracyCheck:
    """:func:`check_accuracy`'s result: one record per decoded node, in program order."""

    nodes: list[NodeAccuracy] = field(default_factory=list)
    n_frames: int = 0
    skipped: str | None = None

    def warnings(self) -> list[str]:
        """One line per node whose figure is large (empty when all are within bounds)."""
        return [a.describe() for a in self.nodes if a.large]

    def to_dict(self) -> dict:
        """JSON-able: ``{"n_frames", "skipped", "nodes": [{node, motif, kind, error, …}]}``."""
        return {"n_frames": self.n_frames, "skipped": self.skipped,
                "nodes": [{**a.__dict__, "large": a.large} for a in self.nodes]}


def check_accuracy(program: CompiledProgram, inputs: Mapping[str, np.ndarray], *,
                   max_frames: int = 4, max_time_s: float | None = 10.0) -> AccuracyCheck:
    """Compare every value the program's spiking segments decode with the reference interpreter.

    Parameters
    ----------
    program : CompiledProgram
        A compiled chain (any target).
    inputs : mapping of str to ndarray
        Sample inputs by input node id, one frame or a leading frames axis (e.g. the
        calibration inputs); values above an encoder's range are clipped, as
        ``radarsnn run`` does by default.
    max_frames : int
        Check at most this many frames (the first ones).
    max_time_s : float or None
        The simulator's time guard per frame: a program too slow to check is skipped
        (:attr:`AccuracyCheck.skipped` says why) rather than run for minutes.

    Returns
    -------
    AccuracyCheck
        One :class:`NodeAccuracy` per decoded node of every spiking segment.

    Raises
    ------
    IRError, SimulationError
        Inputs that do not fit the program's graph (naming the input); a ``program`` that
        is not a :class:`~compiler.program.CompiledProgram`.
    """
    if not isinstance(program, CompiledProgram):
        raise SimulationError(f"check_accuracy(program={short_repr(program)}): takes a "
                              f"CompiledProgram, not {type(program).__name__}; compile one with "
                              "compile_graph")
    if not isinstance(inputs, Mapping):
        raise SimulationError(f"check_accuracy: inputs must be a mapping of input node id to "
                              f"array, not {type(inputs).__name__}")
    graph = program.graph
    types = graph.infer_types()
    count = n_frames(types, inputs, f"program {graph.name!r}")
    if count is not None and count > max_frames:
        inputs = {k: np.asarray(v)[:max_frames] for k, v in inputs.items()}
        count = max_frames
    try:
        run = run_program(program, inputs, out_of_range="clip", max_time_s=max_time_s)
    except RadarSNNError as err:
        if "over max_time_s" not in str(err):
            raise
        return AccuracyCheck(n_frames=count or 1, skipped=" ".join(str(err).split()))
    reference = evaluate(graph, inputs, registry=program.evaluators)
    motifs = program.records.motifs
    out = []
    for seg in program.segments:
        if seg.kind != "spiking":
            continue
        for node in seg.outputs:
            if node in run.normalized:  # per-input policy, several inputs mixed: no common unit
                continue
            got, want = np.asarray(run.values[node]), np.asarray(reference[node])
            motif = str(motifs.get(node, "?"))
            if want.dtype == bool:
                got = got != 0
                out.append(NodeAccuracy(node=node, motif=motif, kind="decisions",
                                        error=float(np.mean(got != want)),
                                        differing=int(np.sum(got != want)),
                                        spiking=int(got.sum()), conventional=int(want.sum())))
            else:
                scale = float(np.linalg.norm(want.ravel()))
                err = float(np.linalg.norm((got - want).ravel()))
                out.append(NodeAccuracy(node=node, motif=motif, kind="values",
                                        error=err / scale if scale > 0 else float(err > 0)))
    return AccuracyCheck(nodes=out, n_frames=count or 1)
