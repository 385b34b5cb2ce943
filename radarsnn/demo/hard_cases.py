"""Hard cases: a scene case, the chain it tests, and the spiking-vs-conventional score.

Each :class:`HardCase` pairs a seeded scene of :data:`radar.scene_cases.SCENE_CASES` with
a conventional chain of :mod:`compiler.chains`. :func:`measure_case` compiles the chain for
a target **calibrated on frames of other seeds** (other targets, other noise), runs it on
the measured seeds and scores both chains:

* cell sensitivity / precision of the spiking detections against the conventional ones,
  ``|S ∩ C| / |C|`` and ``|S ∩ C| / |S|``;
* ground-truth targets found (± 1 bin, :mod:`radarsnn.demo.matching`) by each chain — for a
  range-profile chain (no Doppler DFT) each (target, chirp) pair counts, the target's bin
  following its range migration (:func:`radar.scene.chirp_range_bins`);
* *firm* targets: those the conventional chain still finds with its CFAR threshold 1 dB
  higher (:func:`compiler.accuracy.contract.firm_detections`), and how many of them the
  spiking chain misses (a target right at the threshold flips under any rounding, as
  between two runs of a sensor; a firm one must be kept);
* false objects (peaks matching no target, off zero Doppler and beyond the leakage's range
  bins 0-2) of each chain;
* the spiking run's clipped inputs (``ProgramResult.clipped``) and the ADC's clipped rails.

Examples
--------
>>> sorted(HARD_CASES)  # doctest: +NORMALIZE_WHITESPACE
['chirp_sequence_1d', 'high_noise', 'leaky_mimo', 'leaky_mimo_ca', 'range_migration',
 'saturated_mimo']
>>> HARD_CASES["leaky_mimo_ca"].scene
'leaky_mimo'
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np

from backends.reference import ReferenceSimulator, run_program
from compiler.accuracy.contract import firm_detections
from compiler.chains import CA_CFAR, range_cfar_chain, range_doppler_chain
from compiler.compile import compile_graph
from compiler.hardware import load_profile
from ir import Graph, evaluate
from ir.errors import BudgetError, RadarConfigError
from radar.config import RadarConfig
from radar.scene import Frame, chirp_range_bins
from radar.scene_cases import SCENE_CASES
from radarsnn.demo.matching import range_peak_hits, score_peaks, score_range_peaks

__all__ = ["HARD_CASES", "CaseScore", "HardCase", "compile_for", "measure_case",
           "score_frame"]


#: Peaks below this range bin are the near-range leakage (at 0-2 bins in every case), not
#: false objects.
STATIC_RANGE_BINS = 3


@dataclass(frozen=True)
class HardCase:
    """A scene case of :data:`radar.scene_cases.SCENE_CASES` and the chain run on it.

    ``kind`` is ``"map"`` for range-Doppler chains (``det`` has ``range`` and ``doppler``
    axes, power node ``rd``) and ``"profile"`` for per-chirp range chains (``det`` is
    ``[chirp, range]``, power node ``rp``).
    """

    name: str
    scene: str
    chain: Callable[[RadarConfig], Graph]
    kind: Literal["map", "profile"]
    summary: str


HARD_CASES: dict[str, HardCase] = {c.name: c for c in (
    HardCase("leaky_mimo", "leaky_mimo", range_doppler_chain, "map",
             "range-Doppler + OS-CFAR (the default chain)"),
    HardCase("leaky_mimo_ca", "leaky_mimo", lambda cfg: range_doppler_chain(cfg, cfar=CA_CFAR),
             "map", "range-Doppler + CA-CFAR on linear power"),
    HardCase("saturated_mimo", "saturated_mimo", range_doppler_chain, "map",
             "range-Doppler + OS-CFAR on a clipping ADC"),
    HardCase("high_noise", "high_noise", range_doppler_chain, "map",
             "range-Doppler + OS-CFAR, targets near the threshold"),
    HardCase("range_migration", "range_migration", range_doppler_chain, "map",
             "range-Doppler + OS-CFAR, targets crossing range bins"),
    HardCase("chirp_sequence_1d", "chirp_sequence_1d", range_cfar_chain, "profile",
             "range DFT + OS-CFAR per chirp, no Doppler DFT"),
)}
"""Case name -> :class:`HardCase`."""


@dataclass
class CaseScore:
    """Totals of one case on one target over the measured frames (see the module docstring).

    For ``profile`` cases ``truth``, ``conv_found`` and ``spk_found`` count (target, chirp)
    pairs.
    """

    case: str
    target: str
    motifs: dict[str, str]
    seeds: list[int]
    frames: int = 0
    conv_cells: int = 0
    spk_cells: int = 0
    both_cells: int = 0
    truth: int = 0
    conv_found: int = 0
    spk_found: int = 0
    conv_false: int = 0
    spk_false: int = 0
    firm_found: int = 0
    firm_missed: int = 0
    clipped_inputs: int = 0
    adc_clipped: int = 0
    compile_s: float = 0.0
    run_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def sensitivity(self) -> float | None:
        """``|S ∩ C| / |C|`` (None without conventional cells)."""
        return self.both_cells / self.conv_cells if self.conv_cells else None

    @property
    def precision(self) -> float | None:
        """``|S ∩ C| / |S|`` (None without spiking cells)."""
        return self.both_cells / self.spk_cells if self.spk_cells else None

    def as_dict(self) -> dict[str, Any]:
        """The totals and the ratios, JSON-ready."""
        return {**asdict(self), "sensitivity": self.sensitivity, "precision": self.precision,
                "conv_false_per_frame": self.conv_false / max(self.frames, 1),
                "spk_false_per_frame": self.spk_false / max(self.frames, 1)}


def _axes_to(values: Mapping, graph: Graph, node: str, order: Sequence[str]) -> np.ndarray:
    axes = list(graph.infer_types()[node].axes)
    return np.asarray(values[node]).transpose([axes.index(a) for a in order])


def score_frame(kind: str, frame: Frame, graph: Graph, conv: Mapping, spk_graph: Graph,
                spk: Mapping) -> dict[str, int]:
    """One frame's counts: cells of each chain and of both, truth found, false objects.

    ``conv`` and ``spk`` are the values of the conventional and the spiking chain
    (node id -> array) on ``frame``.
    """
    order, power = (("range", "doppler"), "rd") if kind == "map" else (("chirp", "range"), "rp")
    c = _axes_to(conv, graph, "det", order).astype(bool)
    s = _axes_to(spk, spk_graph, "det", order).astype(bool)
    pc = _axes_to(conv, graph, power, order)
    ps = _axes_to(spk, spk_graph, power, order)
    (src,) = graph.inputs_of("det")
    f = _axes_to({"det": firm_detections(graph, "det", conv[src])}, graph, "det", order)
    out = {"conv_cells": int(c.sum()), "spk_cells": int(s.sum()), "both_cells": int((c & s).sum())}
    if kind == "map":
        truth = [(int(t.range_bin), int(t.doppler_bin)) for t in frame.truth]
        cs, ss, fs = (score_peaks(m, p, truth, static_range_bins=STATIC_RANGE_BINS)
                      for m, p in ((c, pc), (s, ps), (f, pc)))
        firm = [x is not None for x in fs.found]
        return {**out, "truth": len(truth), "conv_found": cs.n_found, "spk_found": ss.n_found,
                "conv_false": cs.n_false, "spk_false": ss.n_false, "firm_found": sum(firm),
                "firm_missed": sum(a and b is None for a, b in zip(firm, ss.found,
                                                                   strict=True))}
    bins = [chirp_range_bins(frame.config, t) for t in frame.truth]
    cs, ss = (score_range_peaks(m, p, bins, static_bins=STATIC_RANGE_BINS)
              for m, p in ((c, pc), (s, ps)))
    firm, hit = range_peak_hits(f, pc, bins), range_peak_hits(s, ps, bins)
    return {**out, "truth": len(bins) * cs.n_chirps, "conv_found": sum(cs.hits),
            "spk_found": sum(ss.hits), "conv_false": cs.n_false, "spk_false": ss.n_false,
            "firm_found": int(firm.sum()), "firm_missed": int((firm & ~hit).sum())}


def compile_for(graph: Graph, target: str, calibration_inputs: Mapping[str, np.ndarray], *,
                motifs: Mapping[str, str] | None = None, options: Mapping[str, Any] | None = None,
                measured: bool = False) -> tuple[Any, str | None]:
    """Compile for ``target`` (``"unbounded"``: no profile); on a ``BudgetError`` retry on a
    board of 4, 16 then 64 chips (accuracy does not depend on the placement).

    ``measured``: the compile measures the accuracy contract on the last calibration frames
    (held back) and picks the motifs (``motifs="auto"``, :mod:`compiler.accuracy`), keeping
    the best configuration where none holds (``accuracy="warn"``: the score says so).

    Returns
    -------
    (CompiledProgram, str or None)
        The program and a note naming the board, if one was needed.
    """
    profile = None if target == "unbounded" else load_profile(target)
    chips = 1
    while True:
        p = profile if profile is None or chips == 1 else profile.model_copy(
            update={"chips": chips, "name": f"{profile.name}x{chips}"})
        try:
            program = compile_graph(graph, p, calibration_inputs=calibration_inputs,
                                    motifs=dict(motifs or {}), options=options,
                                    **({"simulator": ReferenceSimulator(), "accuracy": "warn"}
                                       if measured else {}))
        except BudgetError:
            if profile is None or chips == 64:
                raise
            chips *= 4
            continue
        return program, (f"needs {chips} {target} chips (board)" if chips > 1 else None)


def measure_case(name: str, target: str = "loihi2", *, seeds: Sequence[int] = (0, 1, 2),
                 calibration_seeds: Sequence[int] = (100, 101),
                 motifs: Mapping[str, str] | None = None,
                 options: Mapping[str, Any] | None = None,
                 measured: bool = False) -> CaseScore:
    """Compile case ``name``'s chain for ``target`` calibrated on ``calibration_seeds``,
    run it on ``seeds`` and score it (the two seed sets must not overlap).

    Raises
    ------
    RadarConfigError
        ``name`` is not in :data:`HARD_CASES`, or the measured seeds include a
        calibration seed.
    """
    if name not in HARD_CASES:
        raise RadarConfigError(f"unknown hard case {name!r}; cases: {', '.join(HARD_CASES)}")
    if set(seeds) & set(calibration_seeds):
        raise RadarConfigError(f"seeds {sorted(set(seeds) & set(calibration_seeds))} are also "
                         "calibration seeds; measure on frames the calibration did not see")
    case = HARD_CASES[name]
    scene = SCENE_CASES[case.scene]
    graph = case.chain(scene.config())
    (adc,) = (n for n in graph.topological_order() if graph.op(n).op == "adc_input")
    score = CaseScore(case=name, target=target, motifs=dict(motifs or {}), seeds=list(seeds))
    t0 = time.perf_counter()
    program, note = compile_for(graph, target, {adc: scene.cube(calibration_seeds)},
                                motifs=motifs, options=options, measured=measured)
    score.compile_s = time.perf_counter() - t0
    if note:
        score.notes.append(note)
    if measured:  # what the search chose, and whether its contract holds
        sel = program.records.extra["motif_selection"]
        chosen = sel["attempts"][sel["chosen"]]
        score.notes.append(f"auto: {chosen['config']}"
                           + ("" if chosen["holds"] else " (contract FAILS: "
                              + "; ".join(chosen["failures"]) + ")")
                           + ("" if chosen["fits"] is not False else " (over the frame period)"))
    t0 = time.perf_counter()
    for seed in seeds:
        frame = scene.frame(seed)
        conv = evaluate(graph, {adc: frame.adc})
        res = run_program(program, {adc: frame.adc}, mode="auto", out_of_range="clip")
        for key, value in score_frame(case.kind, frame, graph, conv, program.graph,
                                      res.values).items():
            setattr(score, key, getattr(score, key) + value)
        score.clipped_inputs += int(sum(res.clipped.values()))
        score.adc_clipped += frame.n_clipped
        score.frames += 1
    score.run_s = time.perf_counter() - t0
    return score
