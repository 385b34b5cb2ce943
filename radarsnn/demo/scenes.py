"""One demo scene: conventional and spiking range-Doppler-CFAR chains side by side.

For a radar preset: simulate its scene (seeded) and three other frames for
calibration, build :func:`compiler.chains.range_doppler_chain`, evaluate it
with the reference interpreter (the conventional chain), compile it for the
target as a user's compile does — measured: the last calibration frame is held
back, every spiking stage is checked on it against the conventional chain and the
motifs are chosen to keep the contract and the frame deadline (``motifs="auto"``,
docs/accuracy.md) — and run it on the reference simulator (the spiking chain); a
target on which nothing holds or fits is reported with the compiler's typed error
(naming the stage, or the network and its steps). Then score
both against the ground truth (:mod:`radarsnn.demo.matching`) and the spiking
detections against the conventional ones cell by cell:

.. math:: \\text{sensitivity} = \\frac{|S \\cap C|}{|C|}, \\qquad
          \\text{precision} = \\frac{|S \\cap C|}{|S|}

with :math:`S` the spiking and :math:`C` the conventional detected cells.  The
spectrum RMSE (whichever DFT motif) is
:func:`~compiler.lowering.dft_common.modulus_rmse` of the 2-D spectrum (moduli min–max
normalised over the whole map).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from backends.reference import ReferenceSimulator, run_program
from compiler.chains import range_doppler_chain
from compiler.compile import compile_graph
from compiler.lowering.dft_common import modulus_rmse
from ir import evaluate
from ir.errors import AccuracyError, BudgetError
from radar.config import preset
from radar.scene import SCENE_PRESETS, simulate_frame
from radarsnn.demo.matching import score_peaks

__all__ = ["SceneArrays", "SceneReport", "TargetRow", "run_scene"]

#: Offset between a scene's seed and the seed of its first calibration frame.
CALIBRATION_SEED_OFFSET = 1000

#: Calibration frames (other noise seeds); the last is held back for the accuracy check.
CALIBRATION_FRAMES = 3


@dataclass
class TargetRow:
    """One ground-truth target and the peaks matched to it (conventional and spiking)."""

    range_m: float
    velocity_mps: float
    rcs_dbsm: float
    range_bin: int
    doppler_bin: int
    aliased: bool
    found_range_bin: int | None
    found_doppler_bin: int | None
    spiking_range_bin: int | None = None
    spiking_doppler_bin: int | None = None
    lost_at: str | None = None

    @property
    def found(self) -> bool:
        """Whether a conventional detection peak lies within ± 1 bin of the truth."""
        return self.found_range_bin is not None

    @property
    def found_spiking(self) -> bool:
        """Whether a spiking detection peak lies within ± 1 bin of the truth."""
        return self.spiking_range_bin is not None


@dataclass
class SceneReport:
    """The demo's result for one preset (conventional ``n_*``; spiking ``spiking_*``)."""

    preset: str
    chain: str
    map_shape: tuple[int, int]
    """The RD map's shape in the chain's axis order (``map_axes``), as its arrays hold it."""
    targets: list[TargetRow]
    n_peaks: int
    n_clutter: int
    n_false: int
    seconds: float
    target: str | None = None
    spiking_n_peaks: int = 0
    spiking_n_clutter: int = 0
    spiking_n_false: int = 0
    cells_conventional: int = 0
    cells_spiking: int = 0
    cell_sensitivity: float | None = None
    cell_precision: float | None = None
    sft_rmse: float | None = None
    resources: dict[str, Any] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)
    map_axes: tuple[str, ...] = ("doppler", "range")
    accuracy: list[str] = field(default_factory=list)
    """The compile's accuracy contract, one line per spiking stage (``Contract.lines``)."""
    motifs: dict[str, str] = field(default_factory=dict)
    """The motif chosen per node (``motifs="auto"``)."""
    refused: str | None = None
    """The compiler's typed error when no configuration holds or fits (nothing was run)."""

    @property
    def n_targets(self) -> int:
        """Ground-truth targets in the scene."""
        return len(self.targets)

    @property
    def n_found(self) -> int:
        """Targets with a conventional detection within ± 1 bin."""
        return sum(t.found for t in self.targets)

    @property
    def spiking_n_found(self) -> int:
        """Targets with a spiking detection within ± 1 bin."""
        return sum(t.found_spiking for t in self.targets)


@dataclass
class SceneArrays:
    """What the figures need: maps, masks, truth bins, spike times, the report."""

    conventional_db: np.ndarray
    spiking_db: np.ndarray | None
    conventional_mask: np.ndarray
    spiking_mask: np.ndarray | None
    truth_bins: list[tuple[int, int]]
    first_spikes: dict[str, np.ndarray] = field(default_factory=dict)
    report: Any = None
    truth_velocity_mps: list[float] = field(default_factory=list)
    truth_aliased: list[bool] = field(default_factory=list)
    spike_shapes: dict[str, dict[str, int]] = field(default_factory=dict)
    step_s: float | None = None


def _range_doppler(values: dict, graph, node: str) -> np.ndarray:
    axes = list(graph.infer_types()[node].axes)
    return np.asarray(values[node]).transpose([axes.index("range"), axes.index("doppler")])


def _db(power: np.ndarray) -> np.ndarray:
    return 10.0 * np.log10(np.maximum(power, 1e-12 * max(float(power.max()), 1e-30)))


def _resources(report) -> dict[str, Any]:
    if report is None:
        return {}
    d = report.data
    out = {k: v for k, v in d["totals"].items() if isinstance(v, int | float)}
    latency = d.get("latency") or {}
    for key in ("total_steps", "total_s", "frame_period_s", "fits", "max_step_s"):
        if key in latency:
            out[f"latency_{key}"] = latency[key]
    steps = [r["step_s"] for r in latency.get("networks", ()) if r.get("step_s")]
    if steps:
        out["latency_step_s"] = steps[0]
    return out


def lost_at(truth: tuple[int, int], conv_power: np.ndarray, spk_power: np.ndarray,
            spk_mask: np.ndarray) -> str:
    """Which stage lost a target the conventional chain finds, and why (± 1 bin around it).

    ``Fourier stages`` when the spiking RD power at the target is more than 3 dB below the
    conventional one (the S-FT's resolution or a saturated/clipped code), else ``CFAR``
    (the value survived; the detector's decision differs).

    Examples
    --------
    >>> p = np.ones((4, 4)); p[1, 1] = 100.0
    >>> lost_at((1, 1), p, p / 10, np.zeros((4, 4), bool))
    'Fourier stages: RD power at the target 10.0 dB below the conventional'
    """
    r, d = truth
    rows = slice(max(0, r - 1), r + 2)
    cols = [(d + k) % conv_power.shape[1] for k in (-1, 0, 1)]
    c = float(conv_power[rows][:, cols].max())
    s = float(spk_power[rows][:, cols].max())
    drop = 10 * np.log10(max(c, 1e-300) / max(s, 1e-300))
    if drop > 3.0:
        return f"Fourier stages: RD power at the target {drop:.1f} dB below the conventional"
    return (f"CFAR: RD power within {abs(drop):.1f} dB of the conventional, but no detection "
            "peak there (the noise estimate of the spiking map differs)")


def run_scene(name: str, seed: int, *, target: str | None = "kapoho_point",
              spiking: bool = True, progress=None) -> tuple[SceneReport, SceneArrays]:
    """Run one preset's scene through the conventional (and spiking) chain and score it.

    Parameters
    ----------
    name : str
        A radar preset with a scene (``seed003``, ``carrada``).
    seed : int
        Noise seed of the scene (the calibration frames use ``seed + 1000`` …
        ``seed + 1002``; the last is held back for the accuracy check).
    target : str or None
        Hardware profile to compile for (None: no allocation, no report).
    spiking : bool
        Also compile and simulate the spiking chain.
    progress : callable, optional
        ``progress(stage, message)``.
    """
    say = progress or (lambda _s, _m: None)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    config = preset(name)
    scene = SCENE_PRESETS[name]()
    frame = simulate_frame(config, scene, seed=seed)
    graph = range_doppler_chain(config)
    conv = evaluate(graph, {"adc": frame.adc})
    timings["conventional"] = time.perf_counter() - start
    say(name, "conventional chain done")
    c_mask, c_power = _range_doppler(conv, graph, "det"), _range_doppler(conv, graph, "rd")
    truth = [(int(t.range_bin), int(t.doppler_bin)) for t in frame.truth]
    c_score = score_peaks(c_mask, c_power, truth)
    det_axes = graph.infer_types()["det"].axes  # the chain's own order: [doppler, range]
    report = SceneReport(preset=name, chain=graph.name, map_shape=tuple(det_axes.values()),
                         map_axes=tuple(det_axes),
                         targets=[], n_peaks=c_score.n_peaks, n_clutter=c_score.n_clutter,
                         n_false=c_score.n_false, seconds=0.0, target=target,
                         cells_conventional=int(c_mask.sum()))
    arrays = SceneArrays(conventional_db=_db(c_power), spiking_db=None, conventional_mask=c_mask,
                         spiking_mask=None, truth_bins=truth,
                         truth_velocity_mps=[float(t.velocity_mps) for t in frame.truth],
                         truth_aliased=[bool(t.aliased) for t in frame.truth])
    s_found, program = [None] * len(truth), None
    if spiking:
        t0 = time.perf_counter()
        seeds = range(seed + CALIBRATION_SEED_OFFSET,
                      seed + CALIBRATION_SEED_OFFSET + CALIBRATION_FRAMES)
        calibration = np.stack([simulate_frame(config, scene, seed=s).adc for s in seeds])
        try:
            program = compile_graph(graph, target, calibration_inputs={"adc": calibration},
                                    simulator=ReferenceSimulator(), progress=progress)
        except (AccuracyError, BudgetError) as err:  # what a user's compile says
            program, report.refused = None, " ".join(str(err).split())
        timings["compile"] = time.perf_counter() - t0
        say(name, f"compiled for {target}" if program else f"refused for {target}")
    if spiking and program is not None:
        report.accuracy = program.records.accuracy.lines()
        report.motifs = {n: str(m) for n, m in program.records.motifs.items()  # not the
                         if program.graph.op(n).op in ("dft", "cfar") and "__static" not in n}
        # static split's exact host copies
        t0 = time.perf_counter()
        # the scene frame may exceed the calibration frame's range by a few ADC codes: clip
        # (explicitly; the default policy refuses them)
        result = run_program(program, {"adc": frame.adc}, mode="auto", out_of_range="clip")
        timings["simulate"] = time.perf_counter() - t0
        say(name, "spiking chain simulated")
        s_mask = _range_doppler(result.values, program.graph, "det").astype(bool)
        s_power = _range_doppler(result.values, program.graph, "rd")
        s_score = score_peaks(s_mask, s_power, truth)
        s_found = s_score.found
        hits = int((s_mask & c_mask).sum())
        report.spiking_n_peaks, report.spiking_n_clutter = s_score.n_peaks, s_score.n_clutter
        report.spiking_n_false, report.cells_spiking = s_score.n_false, int(s_mask.sum())
        report.cell_sensitivity = hits / max(1, int(c_mask.sum()))
        report.cell_precision = hits / max(1, int(s_mask.sum()))
        dop_axes = list(graph.infer_types()["dop"].axes)
        order = [a for a in dop_axes if a != "range"] + ["range"]
        perm = [dop_axes.index(a) for a in order]
        spiking_dop = "dop__moving" if "dop__moving" in result.values else "dop"
        exact = conv if spiking_dop == "dop" else evaluate(program.graph, {"adc": frame.adc})
        # the spiking stages' own error: on the moving part when the static part is exact
        # on the host (static-split), which would otherwise dominate the modulus scale
        report.sft_rmse = modulus_rmse(np.asarray(result.values[spiking_dop]).transpose(perm),
                                       np.asarray(exact[spiking_dop]).transpose(perm),
                                       drop_bin0=False)
        program_report = program.records.report
        report.resources = _resources(program_report)
        arrays.spiking_db, arrays.spiking_mask = _db(s_power), s_mask
        arrays.report = program_report
        # every population, in pipeline order: by its node's place in the graph, then in
        # its network's order (in -> out); the figure shows the first few
        steps_of = {pid: s for sim in result.simulations
                    for pid, s in sim.first_spike_steps.items()}
        topo = {nid: k for k, nid in enumerate(program.graph.topological_order())}
        pops = sorted((p for net in program.networks for p in net.populations
                       if p.id in steps_of),
                      key=lambda p: topo.get(p.origin.get("node"), len(topo)))
        arrays.first_spikes = {p.id: steps_of[p.id][0].reshape(-1) for p in pops}
        arrays.spike_shapes = {p.id: dict(p.shape) for p in pops}
        arrays.step_s = getattr(program.target, "time_step_s", None)
    report.targets = [
        TargetRow(range_m=float(t.range_m), velocity_mps=float(t.velocity_mps),
                  rcs_dbsm=float(t.rcs_dbsm), range_bin=int(t.range_bin),
                  doppler_bin=int(t.doppler_bin), aliased=bool(t.aliased),
                  found_range_bin=None if f is None else f[0],
                  found_doppler_bin=None if f is None else f[1],
                  spiking_range_bin=None if s is None else s[0],
                  spiking_doppler_bin=None if s is None else s[1])
        for t, f, s in zip(frame.truth, c_score.found, s_found, strict=True)]
    if spiking and program is not None:
        for row, tb in zip(report.targets, truth, strict=True):
            if row.found and not row.found_spiking:
                row.lost_at = lost_at(tb, c_power, s_power, s_mask)
    report.timings_s = {k: round(v, 3) for k, v in timings.items()}
    report.seconds = time.perf_counter() - start
    return report, arrays
