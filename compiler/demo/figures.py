"""The demo's figures (matplotlib, Agg): RD maps with detections, spike times.

``rd_maps`` draws the conventional and the spiking range-Doppler map side by
side in physical units (range in m, radial velocity in m/s, from the radar
configuration) on one colour scale: power in dB relative to the noise floor
(the median of the conventional map), from ``-5`` to ``+25`` dB, so that every
cell 25 dB or more above the noise is drawn in the top colour.  Maps larger
than the panel are reduced by the *maximum* over the bins of each pixel, so a
single-cell target never vanishes.  Targets hit, targets missed, false alarms
and static clutter are marked with one hollow marker each (one legend entry per
kind).  ``spike_times`` draws the first spike step of each neuron of the
chain's populations in pipeline order (for the fire-once neurons of the
time-coded motifs this *is* the raster: each spikes at most once).  The core
map is :meth:`compiler.report.Report.save_core_map`.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from compiler.cli.chain import write_output
from compiler.demo.matching import detection_peaks, match_peak

__all__ = ["MARKERS", "rd_figure", "rd_maps", "spike_figure", "spike_times"]

#: Resolution of the figures (the figure's and the PNG's: the pooling needs them equal).
DPI = 110
#: Colour scale of the RD maps, dB relative to the noise floor.
SPAN_DB = (-5.0, 25.0)
#: Marker kind -> (legend label, matplotlib marker, edge colour, size in points).
MARKERS = {
    "hit": ("target detected", "o", "white", 12),
    "miss": ("target missed", "s", "red", 12),
    "false_alarm": ("false alarm", "^", "magenta", 10),
    "clutter": ("static clutter at 0 m/s", "D", "cyan", 4.5),
}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _classify(mask: np.ndarray, db: np.ndarray, truth_bins) -> dict[str, list[tuple[int, int]]]:
    """Bins of each marker kind: truth hit / missed, unmatched peaks off / at zero Doppler."""
    peaks = detection_peaks(mask, db)
    kinds: dict[str, list[tuple[int, int]]] = {k: [] for k in MARKERS}
    matched = set()
    for r, d in truth_bins:
        found = match_peak(peaks, r, d, mask.shape[1])
        kinds["hit" if found is not None else "miss"].append((r, d))
        matched.add(found)
    for p in map(tuple, peaks.tolist()):
        if p not in matched:
            kinds["clutter" if p[1] == mask.shape[1] // 2 else "false_alarm"].append(p)
    return kinds


def _max_pool(db: np.ndarray, f_range: int, f_doppler: int) -> np.ndarray:
    """The maximum over blocks of ``f_range`` × ``f_doppler`` bins (the last block padded)."""
    n_r, n_d = -(-db.shape[0] // f_range), -(-db.shape[1] // f_doppler)
    padded = np.full((n_r * f_range, n_d * f_doppler), -np.inf)
    padded[:db.shape[0], :db.shape[1]] = db
    return padded.reshape(n_r, f_range, n_d, f_doppler).max(axis=(1, 3))


def _pool_to_pixels(fig, ax, image, db: np.ndarray, extent: list[float]) -> tuple[int, int]:
    """Replace ``image``'s data by the max-pooled map when it has more bins than pixels."""
    fig.canvas.draw()
    box = ax.get_window_extent()
    f_r = max(1, int(np.ceil(db.shape[0] / max(1.0, box.height))))
    f_d = max(1, int(np.ceil(db.shape[1] / max(1.0, box.width))))
    if f_r > 1 or f_d > 1:
        pooled = _max_pool(db, f_r, f_d)
        dr = (extent[3] - extent[2]) / db.shape[0]
        dv = (extent[1] - extent[0]) / db.shape[1]
        image.set_data(pooled)
        image.set_extent([extent[0], extent[0] + pooled.shape[1] * f_d * dv,
                          extent[2], extent[2] + pooled.shape[0] * f_r * dr])
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
    return f_r, f_d


def rd_figure(title: str, arrays, config, *, span_db: tuple[float, float] = SPAN_DB):
    """The RD-map figure (conventional, and spiking when present) as a matplotlib Figure.

    Parameters
    ----------
    title : str
        Scene name, the start of the figure's title.
    arrays : compiler.demo.scenes.SceneArrays
        Maps in dB (``[range, doppler]``, Doppler fftshifted), detection masks, truth bins.
    config : radar.config.RadarConfig
        The scene's radar: gives the range (m) and velocity (m/s) of every bin.
    span_db : (float, float)
        Colour scale, dB relative to the noise floor (the conventional map's median).

    Returns
    -------
    matplotlib.figure.Figure
        One image per panel (``ax.images[0]``, its data the plotted dB re noise floor).
    """
    plt = _pyplot()
    panels = [("conventional", arrays.conventional_db, arrays.conventional_mask)]
    if arrays.spiking_db is not None:
        panels.append(("spiking", arrays.spiking_db, arrays.spiking_mask))
    floor_db = float(np.median(arrays.conventional_db))
    range_m, velocity_mps = config.range_axis_m(), config.velocity_axis_mps()
    n_range, n_doppler = arrays.conventional_db.shape
    if (n_range, n_doppler) != (range_m.size, velocity_mps.size):
        raise ValueError(f"RD map {n_range} x {n_doppler} does not match the radar's "
                         f"{range_m.size} range bins x {velocity_mps.size} Doppler bins")
    dr_m, dv_mps = config.range_resolution_m, config.velocity_resolution_mps
    extent = [velocity_mps[0] - dv_mps / 2, velocity_mps[-1] + dv_mps / 2,
              range_m[0] - dr_m / 2, range_m[-1] + dr_m / 2]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels) + 1.2, 6.8), dpi=DPI,
                             squeeze=False, constrained_layout=True)
    image = None
    drawn = []
    for ax, (label, db, mask) in zip(axes[0], panels, strict=True):
        rel = db - floor_db
        image = ax.imshow(rel, origin="lower", aspect="auto", cmap="viridis", extent=extent,
                          vmin=span_db[0], vmax=span_db[1], interpolation="nearest")
        kinds = _classify(mask, db, arrays.truth_bins)
        for kind, (name, marker, colour, size) in MARKERS.items():
            rd = np.array(kinds[kind], dtype=np.int64).reshape(-1, 2)
            ax.plot(velocity_mps[rd[:, 1]], range_m[rd[:, 0]], marker, linestyle="none",
                    markerfacecolor="none", markeredgecolor=colour, markeredgewidth=1.2,
                    markersize=size, label=f"{name} ({len(rd)})")
        n_t = len(arrays.truth_bins)
        ax.set_title(f"{label}: {len(kinds['hit'])}/{n_t} targets, "
                     f"{len(kinds['false_alarm'])} false alarms, {int(mask.sum())} cells",
                     fontsize=10)
        ax.set_xlabel("radial velocity (m/s)")
        ax.set_ylabel("range (m)")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=2, fontsize=8,
                  facecolor="0.85", framealpha=1.0)
        drawn.append((ax, ax.images[0], rel))
    fig.colorbar(image, ax=list(axes[0]), extend="both",
                 label="power re noise floor (dB; floor = median of the conventional map)")
    factors = [_pool_to_pixels(fig, ax, im, rel, extent) for ax, im, rel in drawn]
    pooled = max(factors)
    note = (f"; each pixel the max of {pooled[0]} × {pooled[1]} bins" if pooled != (1, 1)
            else "")
    fig.suptitle(f"{title}: range-Doppler map, {n_range} × {n_doppler} bins of "
                 f"{dr_m:.3g} m × {dv_mps:.3g} m/s (unambiguous ± "
                 f"{config.max_velocity_mps:.3g} m/s){note}", fontsize=11)
    return fig


def rd_maps(path: Path, title: str, arrays, config) -> Path:
    """Write :func:`rd_figure` as a PNG at ``path``; return ``path``."""
    return write_png(path, rd_figure(title, arrays, config))


def _block(steps: np.ndarray, max_neurons: int) -> tuple[int, np.ndarray]:
    """The block of ``max_neurons`` consecutive neurons with the most spikes: (start, steps)."""
    n_blocks = max(1, -(-steps.size // max_neurons))
    padded = np.full(n_blocks * max_neurons, -1, dtype=np.int64)
    padded[:steps.size] = steps
    block = int(np.argmax((padded.reshape(n_blocks, max_neurons) >= 0).sum(axis=1)))
    start = block * max_neurons
    return start, padded[start:min(start + max_neurons, steps.size)]


def spike_figure(title: str, first_spikes: dict[str, np.ndarray], max_neurons: int = 512,
                 max_panels: int = 8):
    """First spike steps of the chain's populations (frame 0), one panel each, in pipeline order.

    Parameters
    ----------
    title : str
        Scene name, the start of the figure's title.
    first_spikes : dict of str to ndarray
        Population id (``node/role``) -> first spike step per neuron (flat, -1: none),
        in pipeline order (the order of the stages through the chain).
    max_neurons : int
        A population with at most ``max_neurons`` spikes is drawn whole; of a busier
        one the block of ``max_neurons`` consecutive neurons (flat index) with the
        most spikes.
    max_panels : int
        At most this many populations (the first ones) are drawn.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per population, titled ``<population id>: ...``, neuron and step
        ticks at integers.
    """
    from matplotlib.ticker import MaxNLocator

    plt = _pyplot()
    items = list(first_spikes.items())[:max_panels]
    n = max(1, len(items))
    last_step = {}  # one time axis per stage (its populations share a window)
    for pid, steps in items:
        node = pid.split("/")[0]
        last_step[node] = max(last_step.get(node, 0), int(steps.max(initial=0)))
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.7 * n + 0.7), squeeze=False)
    for ax, (pid, steps) in zip(axes[:, 0], items, strict=False):
        total = int((steps >= 0).sum())
        if total <= max_neurons:  # sparse: every spike, over the whole population
            start, s = 0, steps
        else:
            start, s = _block(steps, max_neurons)
        fired = np.flatnonzero(s >= 0)
        ax.plot(s[fired], fired + start, "|", markersize=4 if total <= max_neurons else 3,
                color="black")
        right = last_step[pid.split("/")[0]] or max(last_step.values(), default=1)
        ax.set_xlim(-0.5, right + 1.5)
        ax.set_ylim(start - 0.5, start + max(s.size, 1) - 0.5)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.yaxis.set_major_locator(MaxNLocator(nbins=4, integer=True))
        ax.set_ylabel("neuron")
        ax.set_xlabel("time step", fontsize=8)
        if total == 0:
            ax.text(0.5, 0.5, "no spike time recorded in frame 0 (silent, or a graded "
                    "read-out: membranes sent as payloads)", transform=ax.transAxes,
                    ha="center", va="center", color="0.4", fontsize=8)
            ax.set_title(f"{pid}: {steps.size} neurons, no spike", fontsize=9)
        elif total <= max_neurons:
            ax.set_title(f"{pid}: all {steps.size} neurons, {total} spiked", fontsize=9)
        else:
            ax.set_title(f"{pid}: neurons {start}–{start + s.size - 1}, {fired.size} spiked "
                         f"({total} of {steps.size} in all)", fontsize=9)
    fig.suptitle(f"{title}: first spike per neuron (frame 0), stages in pipeline order",
                 fontsize=10)
    fig.tight_layout()
    return fig


def spike_times(path: Path, title: str, first_spikes: dict[str, np.ndarray],
                max_neurons: int = 512) -> Path:
    """Write :func:`spike_figure` as a PNG at ``path``; return ``path``."""
    return write_png(path, spike_figure(title, first_spikes, max_neurons))


def write_png(path: Path, fig) -> Path:
    """Write ``fig`` as a PNG at ``path`` atomically (whole, or the old file kept); close it."""
    png = io.BytesIO()
    fig.savefig(png, dpi=DPI, format="png")
    _pyplot().close(fig)
    write_output(path, png.getvalue(), "a figure")
    return Path(path)
