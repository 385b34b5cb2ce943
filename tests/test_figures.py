"""The pictures as a radar engineer reads them: checked on the rendered pixels and artists.

* RD maps: axes in m and m/s from the radar config, target cells in the top colour
  decile of the rendered image (seed003's 512 x 128 map included), one legend entry
  per marker kind (hit, miss, false alarm, clutter) with the right counts;
* spike rasters: populations in pipeline order, integer ticks;
* core maps: every stage (also one that only shares a core) in the legend, in the
  colour of its patches;
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

from compiler.demo.figures import MARKERS, rd_figure, spike_figure  # noqa: E402
from compiler.demo.scenes import run_scene  # noqa: E402
from compiler.report import Report  # noqa: E402
from compiler.report.core_map import core_map_figure  # noqa: E402
from compiler.sweep.figures import _pareto, pick_cost  # noqa: E402
from compiler.sweep.spec import FigureSpec  # noqa: E402
from radar.config import preset  # noqa: E402


@pytest.fixture(scope="module")
def carrada():
    """The carrada scene through both chains (compiled for loihi2): a few seconds."""
    return run_scene("carrada", 0, spiking=True)


@pytest.fixture(scope="module")
def seed003_conventional():
    """seed003's 512 x 128 map (conventional only: no 10 s compilation)."""
    return run_scene("seed003", 0, spiking=False)[1]


def _colour_fractions(fig, ax, cells, config) -> list[float]:
    """Position in the colour map (0 bottom, 1 top) of each ``(range, doppler)`` cell as drawn.

    Reads the rendered RGBA buffer: the pixels whose centres lie in the cell (or the
    one holding its centre when the cell is smaller than a pixel), each mapped back
    to the nearest colour-map entry; the brightest of them counts.
    """
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)
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
            assert y1 == pytest.approx(config.max_range_m - config.range_resolution_m / 2)
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
            texts = _legend(ax)
            assert len(texts) == len(MARKERS)
            assert [t.rsplit(" (", 1)[0] for t in texts] == names
            handles = ax.get_legend().legend_handles
            assert len({h.get_marker() for h in handles}) == len(MARKERS)
        assert _legend(conv)[:3] == [f"target detected ({n_t})", "target missed (0)",
                                     "false alarm (0)"]
        assert _legend(spk)[:3] == [f"target detected ({n_t - 1})", "target missed (1)",
                                    "false alarm (1)"]
        miss = next(ln for ln in spk.get_lines() if ln.get_label().startswith("target missed"))
        cfg = preset("carrada")
        assert miss.get_ydata()[0] == pytest.approx(cfg.range_axis_m()[r])
        assert miss.get_xdata()[0] == pytest.approx(cfg.velocity_axis_mps()[d])
    finally:
        plt.close(fig)


def test_spike_raster_in_pipeline_order_with_integer_ticks(carrada):
    _, arrays = carrada
    pids = list(arrays.first_spikes)
    nodes = list(dict.fromkeys(p.split("/")[0] for p in pids))
    assert nodes == ["rng__moving", "dop__moving", "det"]
    assert pids.index("rng__moving/in") < pids.index("rng__moving/out")
    assert pids.index("det/in") < pids.index("det/det")
    fig = spike_figure("carrada", arrays.first_spikes)
    try:
        titles = [ax.get_title().split(":")[0] for ax in fig.axes]
        assert titles == pids
        fig.canvas.draw()
        for ax in fig.axes:
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
        assert matplotlib.colors.to_hex(to_rgba("0.92")) in {
            matplotlib.colors.to_hex(p.get_facecolor()) for p in fig.axes[0].patches}
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
