"""The pictures as a radar engineer reads them: checked on the rendered pixels and artists.

* RD maps: axes in m and m/s from the radar config, the range axis cropped to a little
  past the farthest target with every target inside it, target cells in the top colour
  decile of the rendered image (seed003's 512 x 128 map included), each chain's detected
  cells drawn (both / only this chain, distinguishable), aliased targets marked, one
  legend entry per marker kind (hit, miss, false alarm, clutter) with the right counts;
* spike rasters: populations with spikes in pipeline order on one shared time axis in
  steps and µs, neurons by bin, no empty panel, integer ticks;
* core maps: every stage (also one that only shares a core) in the legend, in the
  colour of its stripes; cores coloured by utilisation on one scale, rows labelled by
  chip and core;
* the sweep's Pareto plot: against a cost that varies, saying so when it switched.
"""

from __future__ import annotations

import dataclasses

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from compiler.report import Report  # noqa: E402
from compiler.report.core_map import core_map_figure  # noqa: E402
from radar.config import preset  # noqa: E402
from radarsnn.demo.figures import (  # noqa: E402
    CHAIN_COLOURS,
    MARKERS,
    MARKERS_ALIASED,
    rd_figure,
    shown_range_bins,
)
from radarsnn.demo.rasters import spike_figure  # noqa: E402
from radarsnn.demo.scenes import run_scene  # noqa: E402
from radarsnn.sweep.figures import _pareto, pick_cost  # noqa: E402
from radarsnn.sweep.sections import FigureSpec  # noqa: E402


@pytest.fixture(scope="module")
def carrada():
    """The carrada scene through both chains, compiled as the demo does (measured, for a
    Kapoho Point board: the resonator DFTs): half a minute."""
    return run_scene("carrada", 0, spiking=True)


@pytest.fixture(scope="module")
def seed003_conventional():
    """seed003's 512 x 128 map (conventional only: no 10 s compilation)."""
    return run_scene("seed003", 0, spiking=False)[1]


def _colour_fractions(fig, ax, cells, config) -> list[float]:
    """Position in the colour map (0 bottom, 1 top) of each ``(range, doppler)`` cell as drawn.

    Reads the rendered RGBA buffer: the pixels whose centres lie in the cell (or the
    one holding its centre when the cell is smaller than a pixel), each mapped back
    to the nearest colour-map entry; the brightest of them counts.  The detected-cell
    overlay is hidden while reading (it covers the cells it marks).
    """
    cells_lines = [ln for a in fig.axes for ln in a.get_lines()
                   if (ln.get_gid() or "").startswith("cells:")]
    for ln in cells_lines:
        ln.set_visible(False)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)
    for ln in cells_lines:
        ln.set_visible(True)
    height = rgba.shape[0]
    image = ax.images[0]
    lut = image.cmap(np.linspace(0.0, 1.0, 256))[:, :3] * 255.0
    r_m, v_mps = config.range_axis_m(), config.velocity_axis_mps()
    dr, dv = config.range_resolution_m, config.velocity_resolution_mps
    out = []
    for r, d in cells:
        (x0, y0), (x1, y1) = ax.transData.transform(
            [(v_mps[d] - dv / 2, r_m[r] - dr / 2), (v_mps[d] + dv / 2, r_m[r] + dr / 2)])
        cols = np.arange(int(np.ceil(x0 - 0.5)), int(np.floor(x1 - 0.5)) + 1)
        rows_up = np.arange(int(np.ceil(y0 - 0.5)), int(np.floor(y1 - 0.5)) + 1)
        if cols.size == 0:
            cols = np.array([int((x0 + x1) / 2)])
        if rows_up.size == 0:
            rows_up = np.array([int((y0 + y1) / 2)])
        px = rgba[height - 1 - rows_up][:, cols].reshape(-1, 3)
        dist = np.linalg.norm(px[:, None, :] - lut[None, :, :], axis=2)
        nearest = dist.argmin(axis=1)
        drawn = dist[np.arange(px.shape[0]), nearest] < 12.0  # a map colour, not a marker
        out.append(float(nearest[drawn].max() / 255.0) if drawn.any() else -1.0)
    return out


def _legend(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_seed003_single_cell_targets_are_in_the_top_decile(seed003_conventional):
    arrays = seed003_conventional
    assert arrays.conventional_db.shape == (512, 128)
    # the spiking panel: the same map (the comparison's scale is the conventional floor)
    both = dataclasses.replace(arrays, spiking_db=arrays.conventional_db.copy(),
                               spiking_mask=arrays.conventional_mask.copy())
    config = preset("seed003")
    fig = rd_figure("seed003", both, config)
    try:
        axes = [a for a in fig.axes if a.images]
        assert len(axes) == 2
        for ax in axes:
            fractions = _colour_fractions(fig, ax, arrays.truth_bins, config)
            assert min(fractions) >= 0.9, fractions
            assert ax.images[0].get_clim() == axes[0].images[0].get_clim()  # one scale
        # the noise floor is not painted bright: most of the map is in the lower half
        rel = axes[0].images[0].get_array()
        norm = axes[0].images[0].norm
        assert float(np.mean(norm(rel) >= 0.9)) < 0.01
    finally:
        plt.close(fig)


def test_rd_axes_in_metres_and_metres_per_second(carrada):
    _, arrays = carrada
    config = preset("carrada")
    fig = rd_figure("carrada", arrays, config)
    try:
        axes = [a for a in fig.axes if a.images]
        assert len(axes) == 2
        for ax in axes:
            assert ax.get_xlabel().endswith("(m/s)") and ax.get_ylabel().endswith("(m)")
            x0, x1 = sorted(ax.get_xlim())
            y0, y1 = sorted(ax.get_ylim())
            vmax = config.max_velocity_mps
            assert x0 == pytest.approx(-vmax - config.velocity_resolution_mps / 2)
            assert x1 == pytest.approx(vmax - config.velocity_resolution_mps / 2)
            n_show = shown_range_bins(arrays.truth_bins, config.n_samples)
            assert y1 == pytest.approx(config.range_axis_m()[n_show - 1]
                                       + config.range_resolution_m / 2)
            assert min(_colour_fractions(fig, ax, arrays.truth_bins, config)) >= 0.9
            # markers at the physical position of the targets
            hits = [ln for ln in ax.get_lines() if ln.get_label().startswith("target detected")]
            xs, ys = hits[0].get_data()
            r, d = np.array(arrays.truth_bins).T
            assert sorted(ys) == pytest.approx(sorted(config.range_axis_m()[r]))
            assert sorted(xs) == pytest.approx(sorted(config.velocity_axis_mps()[d]))
        label = fig.axes[-1].get_ylabel()  # the shared colour bar
        assert "dB" in label and "noise floor" in label
    finally:
        plt.close(fig)


def test_one_legend_entry_per_marker_kind(carrada):
    _, arrays = carrada
    (r, d), far = arrays.truth_bins[0], (arrays.truth_bins[0][0], 3)
    mask = arrays.spiking_mask.copy()
    mask[max(0, r - 2):r + 3, [(d + k) % mask.shape[1] for k in range(-2, 3)]] = False  # a miss
    mask[far] = True  # a false alarm off zero Doppler
    db = arrays.spiking_db.copy()
    db[far] = db.max()
    fig = rd_figure("carrada", dataclasses.replace(arrays, spiking_mask=mask, spiking_db=db),
                    preset("carrada"))
    try:
        conv, spk = [a for a in fig.axes if a.images]
        names = [m[0] for m in MARKERS.values()]
        n_t = len(arrays.truth_bins)
        for ax in (conv, spk):
            texts = [t for t in _legend(ax) if t.rsplit(" (", 1)[0] in names]
            assert [t.rsplit(" (", 1)[0] for t in texts] == names
            handles = [h for h, t in zip(ax.get_legend().legend_handles, _legend(ax), strict=True)
                       if t.rsplit(" (", 1)[0] in names]
            assert len({h.get_marker() for h in handles}) == len(MARKERS)
        targets = [t for t in _legend(conv) if t.rsplit(" (", 1)[0] in names]
        assert targets[:3] == [f"target detected ({n_t})", "target missed (0)", "false alarm (0)"]
        targets = [t for t in _legend(spk) if t.rsplit(" (", 1)[0] in names]
        assert targets[:3] == [f"target detected ({n_t - 1})", "target missed (1)",
                               "false alarm (1)"]
        miss = next(ln for ln in spk.get_lines() if ln.get_label().startswith("target missed"))
        cfg = preset("carrada")
        assert miss.get_ydata()[0] == pytest.approx(cfg.range_axis_m()[r])
        assert miss.get_xdata()[0] == pytest.approx(cfg.velocity_axis_mps()[d])
    finally:
        plt.close(fig)


def _shown_cells(ax, gid: str) -> set[tuple[float, float]]:
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == gid]
    return {(round(float(x), 6), round(float(y), 6)) for ln in lines for x, y in ln.get_xydata()}


def test_rd_detections_drawn_and_targets_in_the_shown_range(carrada):
    _, arrays = carrada
    config = preset("carrada")
    r_m, v_mps = config.range_axis_m(), config.velocity_axis_mps()
    # one spiking-only and one conventional-only cell, so both kinds appear
    spk, conv = arrays.spiking_mask.copy(), arrays.conventional_mask.copy()
    spk[30, 5], conv[31, 6], spk[31, 6], conv[30, 5] = True, True, False, False
    fig = rd_figure("carrada", dataclasses.replace(arrays, spiking_mask=spk,
                                                   conventional_mask=conv), config)
    try:
        axes = {ax.get_title().split(":")[0]: ax for ax in fig.axes if ax.images}
        n_show = shown_range_bins(arrays.truth_bins, config.n_samples)
        for label, mask, other in (("conventional", conv, spk), ("spiking", spk, conv)):
            ax = axes[label]
            y0, y1 = sorted(ax.get_ylim())
            for r, _ in arrays.truth_bins:  # every target within the shown range
                assert y0 <= r_m[r] <= y1
            assert y1 < config.max_range_m or n_show == config.n_samples
            def at(cells):
                return {(round(float(v_mps[d]), 6), round(float(r_m[r]), 6)) for r, d in cells}
            both = np.argwhere((mask & other)[:n_show])
            only = np.argwhere((mask & ~other)[:n_show])
            assert _shown_cells(ax, "cells:both") == at(both) and len(both) > 100
            assert _shown_cells(ax, "cells:only") == at(only) and len(only) >= 1
            (line,) = [ln for ln in ax.get_lines() if ln.get_gid() == "cells:only"]
            assert to_rgba(line.get_color()) == to_rgba(CHAIN_COLOURS[label])  # per chain
            assert f"the {label} chain only" in line.get_label()
        assert to_rgba(CHAIN_COLOURS["conventional"]) != to_rgba(CHAIN_COLOURS["spiking"])
    finally:
        plt.close(fig)


def test_seed003_range_axis_is_cropped_to_the_targets(seed003_conventional):
    config = preset("seed003")  # targets at 5, 9 and 100 m of a 0–280 m map
    fig = rd_figure("seed003", seed003_conventional, config)
    try:
        (ax,) = [a for a in fig.axes if a.images]
        top = max(ax.get_ylim())
        assert 100 < top < 0.5 * config.max_range_m
        assert "range bins 0–" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_an_aliased_target_is_marked_aliased(carrada):
    _, arrays = carrada
    config = preset("carrada")
    aliased = [k for k, a in enumerate(arrays.truth_aliased) if a]
    assert aliased  # carrada's 40 m target at -20 m/s, beyond ± 13.5 m/s
    fig = rd_figure("carrada", arrays, config)
    try:
        for ax in (a for a in fig.axes if a.images):
            (line,) = [ln for ln in ax.get_lines() if ln.get_gid() == "aliased"]
            assert line.get_label() == f"{MARKERS_ALIASED[0]} ({len(aliased)})"
            r, d = arrays.truth_bins[aliased[0]]
            assert tuple(line.get_xydata()[0]) == pytest.approx(
                (config.velocity_axis_mps()[d], config.range_axis_m()[r]))
            notes = [t.get_text() for t in ax.texts]
            assert notes == [f"aliased: true {arrays.truth_velocity_mps[aliased[0]]:+.3g} m/s"]
    finally:
        plt.close(fig)


def test_spike_raster_in_pipeline_order_on_one_time_axis_by_bin(carrada):
    _, arrays = carrada
    pids = list(arrays.first_spikes)
    nodes = list(dict.fromkeys(p.split("/")[0] for p in pids))
    assert nodes == ["rng__moving", "dop__moving", "det"]
    assert pids.index("rng__moving/in") < pids.index("rng__moving/out")
    assert pids.index("det/in") < pids.index("det/det")
    silent = [p for p in pids if not np.any(arrays.first_spikes[p] >= 0)]
    # the resonators' graded read-outs: membranes, no spike times
    assert silent == ["rng__moving/out", "dop__moving/out"]
    fig = spike_figure("carrada", arrays.first_spikes, arrays.spike_shapes, step_s=1e-5,
                       focus={"range": arrays.truth_bins[0][0],
                              "doppler": arrays.truth_bins[0][1]}, max_bins=200)
    try:
        panels = [ax for ax in fig.axes if ax.get_title()]
        titles = [ax.get_title().split(":")[0] for ax in panels]
        assert titles == [p for p in pids if p not in silent]  # no empty panel
        assert "rng__moving/out, dop__moving/out" in fig._suptitle.get_text()
        assert len({ax.get_xlim() for ax in panels}) == 1  # one shared time axis
        assert panels[-1].get_xlabel().startswith("time step")
        micro = [c for c in panels[0].child_axes if "µs" in c.get_xlabel()]
        assert micro and "10 µs" in micro[0].get_xlabel()
        labels = [ax.get_ylabel() for ax in panels]
        assert labels == ["bit bin", "range bin", "range bin", "range bin"]
        assert f"at doppler {arrays.truth_bins[0][1]}" in panels[-1].get_title()
        assert max(panels[-1].get_ylim()) == pytest.approx(199.5)  # max_bins range bins
        fig.canvas.draw()
        for ax in panels:
            for ticks in (ax.get_yticks(), ax.get_xticks()):
                assert np.all(ticks == np.round(ticks))
    finally:
        plt.close(fig)


def _patch_colours(ax) -> dict[str, set]:
    out: dict[str, set] = {}
    for p in ax.patches:
        gid = p.get_gid() or ""
        if gid.startswith("stage:"):
            out.setdefault(gid[6:], set()).add(tuple(np.round(p.get_facecolor(), 6)))
    return out


def _check_core_map(data: dict) -> list[str]:
    fig = core_map_figure(data)
    try:
        ax = fig.axes[0]
        legend = ax.get_legend()
        labels = [t.get_text().rsplit(" (", 1)[0] for t in legend.get_texts()]
        colours = {lab: tuple(np.round(h.get_facecolor(), 6))
                   for lab, h in zip(labels, legend.legend_handles, strict=True)}
        on_cores = {s for c in data["cores"] for s in (c.get("stages") or [c["stage"]])}
        assert set(labels) == on_cores and len(labels) == len(on_cores)
        patches = _patch_colours(ax)
        assert set(patches) == on_cores
        # every core coloured by its utilisation on the one colour scale of the colour bar
        cmap = matplotlib.colormaps["viridis"]
        squares = [p for p in ax.patches if p.get_gid() == "core"]
        assert len(squares) == len(data["cores"])
        for sq, c in zip(squares, data["cores"], strict=True):
            util = min(1.0, max(c["utilisation"]))
            assert np.allclose(sq.get_facecolor(), cmap(util))
        assert "utilisation" in fig.axes[1].get_xlabel()
        for stage, cols in patches.items():
            assert cols == {colours[stage]}, stage
        assert len(set(colours.values())) == len(colours)  # distinct
        return labels
    finally:
        plt.close(fig)


def test_core_map_shows_a_stage_that_only_shares_a_core():
    data = {"chain": "c", "target": "t", "cores_per_chip": 8,
            "stages": [{"node": "rng"}, {"node": "dop"}, {"node": "det"}],
            "cores": [{"core": 0, "stage": "rng", "stages": ["rng"], "utilisation": [1.0, 0.2]},
                      {"core": 1, "stage": "rng", "stages": ["rng", "dop"],
                       "utilisation": [0.6, 0.1]},
                      {"core": 2, "stage": "det", "stages": ["det"], "utilisation": [0.01]}]}
    assert _check_core_map(data) == ["rng", "dop", "det"]  # pipeline order
    fig = core_map_figure(data)
    try:
        legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert legend == ["rng (2 cores)", "dop (1 core)", "det (1 core)"]
        assert "1 shared" in fig.axes[0].get_title()
        rows = [t.get_text() for t in fig.axes[0].texts if "cores" in t.get_text()]
        assert rows == ["chip 0, cores 0–2"]  # core and chip indices
        # a 1 % core and a full one differ in colour: the map is not "full" everywhere
        squares = [p for p in fig.axes[0].patches if p.get_gid() == "core"]
        assert not np.allclose(squares[0].get_facecolor(), squares[2].get_facecolor())
    finally:
        plt.close(fig)


def test_core_map_of_the_demo_program(carrada, tmp_path):
    _, arrays = carrada
    report: Report = arrays.report
    for c in report.data["cores"]:
        assert c["stages"][0] == c["stage"]
    assert _check_core_map(report.data) == ["rng__moving", "dop__moving", "det"]
    png = report.save_core_map(tmp_path / "cores.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_pareto_plot_uses_a_cost_that_varies():
    rows = [{"params": {"time_steps": t}, "complete": True, "error": None,
             "metrics": {"cfar": {"sensitivity": 1 - 1 / t}},
             "cost": {"synapses": 2_899_968, "neurons": 16_384, "steps": t, "cores": None}}
            for t in (16, 64, 256)]
    cost, note = pick_cost(rows, "cfar", "synapses")
    assert cost == "steps" and "2,899,968 at every point" in note
    fig = _pareto(plt, rows, FigureSpec(kind="pareto"), {"cfar": "cfar"})
    try:
        ax = fig.axes[0]
        assert "cost.steps" in ax.get_xlabel() and "plotted against cost.steps" in ax.get_title()
        xs = ax.collections[0].get_offsets()[:, 0]
        assert len(set(xs.tolist())) == 3
    finally:
        plt.close(fig)
    varying = [dict(r, cost=dict(r["cost"], synapses=r["params"]["time_steps"])) for r in rows]
    assert pick_cost(varying, "cfar", "synapses") == ("synapses", None)
    flat = [dict(r, cost={"synapses": 5, "steps": 16}) for r in rows]
    fig = _pareto(plt, flat, FigureSpec(kind="pareto"), {"cfar": "cfar"})
    try:
        assert "no trade-off" in fig.axes[0].get_title()
    finally:
        plt.close(fig)
