"""``radarsnn demo``: simulated scenes through the conventional and the spiking chain.

For each radar preset (``seed003``, ``carrada``) the demo simulates its scene,
runs the range-Doppler-CFAR chain (:func:`compiler.chains.range_doppler_chain`)
conventionally and compiled for a target (a Kapoho Point board, 8 Loihi 2 chips, by
default) the way a user's compile does — measured on a held-back calibration frame,
motifs chosen to keep the accuracy contract and the frame deadline — on the
reference simulator, and reports the per-stage accuracy lines of the compile, the
detections of both against the ground truth, the spiking detections against the
conventional ones, the spectrum RMSE (the spiking DFTs against the exact spectrum) and the
resource report
(:mod:`radarsnn.demo.scenes`); a target on which no configuration holds or fits
(carrada on one ``loihi2`` chip) shows the compiler's refusal instead.  With ``out_dir`` it writes
figures and a one-page Markdown summary (:mod:`radarsnn.demo.figures`).

Examples
--------
>>> report = run_demo(seed=0, presets=["carrada"], spiking=False)
>>> report.scenes[0].preset, report.scenes[0].n_found == report.scenes[0].n_targets
('carrada', True)
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

from backends.atomic import check_output
from compiler.report.render import latency_line, totals_line
from radar.config import preset
from radarsnn.cli.chain import write_output
from radarsnn.demo.figures import rd_maps, shown_range_bins
from radarsnn.demo.matching import detection_peaks, score_peaks
from radarsnn.demo.rasters import spike_times
from radarsnn.demo.scenes import SceneReport, TargetRow, run_scene

__all__ = ["DEFAULT_TARGET", "DemoReport", "SceneReport", "TargetRow", "detection_peaks",
           "run_demo", "score_peaks"]

PRESETS = ("seed003", "carrada")


def _fmt(x, spec: str = ".3f") -> str:
    return "-" if x is None else format(x, spec)


def _latency(resources: dict) -> str:
    """The report's latency line from a scene's ``latency_*`` resources."""
    lat = {k[len("latency_"):]: v for k, v in resources.items() if k.startswith("latency_")}
    return latency_line({**lat, "networks": [{"step_s": lat.get("step_s")}]})


@dataclass
class DemoReport:
    """All scenes of one demo run, printable as text, JSON or a Markdown page."""

    seed: int
    scenes: list[SceneReport] = field(default_factory=list)
    files: list[str] = field(default_factory=list)

    def to_text(self) -> str:
        """A readable table per scene."""
        lines = []
        for s in self.scenes:
            lines.append(f"== {s.preset}: chain {s.chain!r}, RD map "
                         f"{' x '.join(map(str, s.map_shape))} ({' x '.join(s.map_axes)}), "
                         f"seed {self.seed}, "
                         f"{s.seconds:.2f} s")
            lines.append(f"  {'range_m':>8} {'v_mps':>7} {'rcs':>5}  {'truth bin':>11}  "
                         f"{'conventional':>12}  {'spiking':>10}  status")
            for t in s.targets:
                truth = f"({t.range_bin},{t.doppler_bin})"
                got = f"({t.found_range_bin},{t.found_doppler_bin})" if t.found else "-"
                spk = (f"({t.spiking_range_bin},{t.spiking_doppler_bin})" if t.found_spiking
                       else "-")
                status = "found" if t.found else "MISSED"
                if s.target is not None and not s.refused:
                    status += ", spiking " + ("found" if t.found_spiking else "MISSED")
                if t.aliased:
                    status += " (aliased Doppler)"
                lines.append(f"  {t.range_m:8.2f} {t.velocity_mps:7.2f} {t.rcs_dbsm:5.1f}  "
                             f"{truth:>11}  {got:>12}  {spk:>10}  {status}")
                if t.lost_at:
                    lines.append(f"           lost by the spiking chain at the {t.lost_at}")
            lines.append(f"  conventional: found {s.n_found}/{s.n_targets} targets; {s.n_peaks} "
                         f"detection peaks: {s.n_clutter} static clutter (zero Doppler), "
                         f"{s.n_false} elsewhere not at a target")
            if s.target is not None and s.refused:
                lines.append(f"  spiking ({s.target}): refused by the compiler: {s.refused}")
            elif s.target is not None:
                lines.append("  compiled measured, motifs " + ", ".join(
                    f"{n}={m}" for n, m in s.motifs.items()) + "; " + s.accuracy[0])
                lines += [f"  {line}" for line in s.accuracy[1:]]
                lines.append(
                    f"  spiking ({s.target}): found {s.spiking_n_found}/{s.n_targets} targets; "
                    f"{s.spiking_n_peaks} peaks: {s.spiking_n_clutter} clutter, "
                    f"{s.spiking_n_false} elsewhere; cells vs conventional: sensitivity "
                    f"{_fmt(s.cell_sensitivity)}, precision {_fmt(s.cell_precision)} "
                    f"({s.cells_spiking} spiking / {s.cells_conventional} conventional cells); "
                    f"spectrum RMSE {_fmt(s.sft_rmse, '.4f')}")
            if s.target is not None:
                r = s.resources
                if r:
                    lines.append(f"  resources on {s.target}: {totals_line(r)}")
                    if "latency_frame_period_s" in r:
                        lines.append("  " + _latency(r))
                lines.append("  time: " + ", ".join(f"{k} {v:.2f} s"
                                                    for k, v in s.timings_s.items()))
        if self.files:
            lines.append("wrote: " + ", ".join(self.files))
        return "\n".join(lines)

    def to_json(self) -> str:
        """The report as a JSON document."""
        return json.dumps(asdict(self), indent=2, sort_keys=True, default=str)

    def to_markdown(self) -> str:
        """The one-page summary the demo writes as ``summary.md``."""
        lines = [f"# radarsnn demo (seed {self.seed})", ""]
        for s in self.scenes:
            lines += [f"## {s.preset}: `{s.chain}` on {s.target or 'no target'}", "",
                      "| range m | v m/s | truth bin | conventional | spiking |",
                      "|---|---|---|---|---|"]
            for t in s.targets:
                conv = f"({t.found_range_bin}, {t.found_doppler_bin})" if t.found else "missed"
                spk = (f"({t.spiking_range_bin}, {t.spiking_doppler_bin})" if t.found_spiking
                       else "not run" if s.target is None or s.refused else "missed")
                lines.append(f"| {t.range_m:.2f} | {t.velocity_mps:.2f} | ({t.range_bin}, "
                             f"{t.doppler_bin}) | {conv} | {spk} |")
            lines += ["", f"- conventional: {s.n_found}/{s.n_targets} targets, {s.n_false} false "
                      f"alarm peaks, {s.n_clutter} clutter peaks"]
            if s.target is not None and s.refused:
                lines += [f"- spiking: refused by the compiler: {s.refused}"]
            elif s.target is not None:
                chosen = ", ".join(f"`{n}={m}`" for n, m in s.motifs.items())
                lines += [f"- compiled measured (motifs {chosen}): {s.accuracy[0]}",
                          *[f"  - `{line.strip()}`" for line in s.accuracy[1:]]]
                lines += [f"- spiking: {s.spiking_n_found}/{s.n_targets} targets, "
                          f"{s.spiking_n_false} false alarm peaks; cell sensitivity "
                          f"{_fmt(s.cell_sensitivity)}, precision {_fmt(s.cell_precision)}; "
                          f"spectrum RMSE {_fmt(s.sft_rmse, '.4f')}",
                          f"- resources: {totals_line(s.resources)}"]
                if "latency_frame_period_s" in s.resources:
                    lines += [f"- real time: {_latency(s.resources)}"]
            lines += ["", f"![RD maps](rd_{s.preset}.png)", ""]
            if s.target is not None and not s.refused:
                lines += [f"![spike times](spikes_{s.preset}.png)", "",
                          f"![cores](cores_{s.preset}.png) — full report: "
                          f"[report_{s.preset}.md](report_{s.preset}.md)", ""]
        return "\n".join(lines)


#: The demo's default target: a board on which both scenes' measured chains fit 10 frames/s
#: (on one loihi2 chip the carrada chain does not: the compile refuses, naming the stage).
DEFAULT_TARGET = "kapoho_point"


def run_demo(seed: int = 0, presets: list[str] | None = None, *,
             target: str | None = DEFAULT_TARGET,
             spiking: bool = True, out_dir: str | Path | None = None,
             progress=None) -> DemoReport:
    """Run the demo on the given presets (default ``seed003`` and ``carrada``).

    Parameters
    ----------
    seed : int
        Scene noise seed.
    presets : list of str, optional
        Radar presets with scenes.
    target : str or None
        Profile or board to compile the spiking chain for (default :data:`DEFAULT_TARGET`).
    spiking : bool
        Also compile and simulate the spiking chain (False: conventional only, fast).
    out_dir : path, optional
        Write ``rd_<preset>.png``, ``spikes_<preset>.png``, ``cores_<preset>.png``,
        ``report_<preset>.md`` and ``summary.md`` there.
    progress : callable, optional
        ``progress(stage, message)``.
    """
    report = DemoReport(seed=seed)
    out = None if out_dir is None else check_output(out_dir, folder=True)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    for name in presets or PRESETS:
        scene, arrays = run_scene(name, seed, target=target, spiking=spiking, progress=progress)
        if not spiking:  # no spiking chain ran: nothing to report for it
            scene.target = None
        report.scenes.append(scene)
        if out is None:
            continue
        files = [rd_maps(out / f"rd_{name}.png", name, arrays, preset(name))]
        if arrays.first_spikes:
            focus = {"rx": 0, **(dict(zip(("range", "doppler"), arrays.truth_bins[0],
                                          strict=True)) if arrays.truth_bins else {})}
            files.append(spike_times(
                out / f"spikes_{name}.png", name, arrays.first_spikes, arrays.spike_shapes,
                step_s=arrays.step_s, focus=focus,
                max_bins=shown_range_bins(arrays.truth_bins, arrays.conventional_db.shape[0])))
        if arrays.report is not None:
            cores = out / f"cores_{name}.png"
            write_output(cores, arrays.report.core_map_png(), "the core map")
            md = out / f"report_{name}.md"
            write_output(md, arrays.report.to_markdown().encode("utf-8"), "the report")
            files += [cores, md]
        report.files += [str(f) for f in files]
    if out is not None:
        summary = out / "summary.md"
        write_output(summary, report.to_markdown().encode("utf-8"), "the summary")
        report.files.append(str(summary))
    return report
