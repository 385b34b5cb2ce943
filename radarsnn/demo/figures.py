"""The demo's figures (matplotlib, Agg): RD maps with detections (spike rasters:
:mod:`radarsnn.demo.rasters`; core maps: :mod:`compiler.report.core_map`).

``rd_maps`` draws the conventional and the spiking range-Doppler map side by
side in physical units (range in m, radial velocity in m/s, from the radar
configuration) on one colour scale: power in dB relative to the noise floor
(the median of the conventional map), from ``-5`` to ``+25`` dB, so that every
cell 25 dB or more above the noise is drawn in the top colour.  The range axis
stops a little past the farthest target (:func:`shown_range_bins`).  Maps larger
than the panel are reduced by the *maximum* over the bins of each pixel, so a
single-cell target never vanishes.  Each panel overlays its chain's detected
cells (:data:`CELL_MARKERS`: the cells both chains detect, and in the chain's
colour — :data:`CHAIN_COLOURS` — the cells only it detects), and marks targets
hit, targets missed, false alarms and static clutter with one hollow marker each
(:data:`MARKERS`, one legend entry per kind) and every aliased target
(:data:`MARKERS_ALIASED`, annotated with its true velocity).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from radarsnn.cli.chain import write_output
from radarsnn.demo.matching import detection_peaks, match_peak

__all__ = ["CELL_MARKERS", "CHAIN_COLOURS", "MARKERS", "MARKERS_ALIASED", "detection_cells",
           "rd_figure", "rd_maps", "shown_range_bins"]

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
#: The aliased-target marker (drawn over the hit / miss marker): label, marker, colour, size.
MARKERS_ALIASED = ("target aliased in Doppler", "*", "orange", 15)
#: Detected-cell kind -> (legend label, marker, colour, size); ``only`` takes the chain's colour.
CELL_MARKERS = {
    "cell": ("detected cell", ".", "white", 3.0),
    "both": ("cell detected by both chains", ".", "white", 3.0),
    "only": ("cell detected by the {chain} chain only", "x", None, 5.0),
}
#: The colour of the cells only one chain detects.
CHAIN_COLOURS = {"conventional": "orange", "spiking": "red"}


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


def shown_range_bins(truth_bins, n_range: int, *, margin: float = 1.25,
                     min_bins: int = 16) -> int:
    """How many range bins (from bin 0) the RD figure shows: to a little past the farthest target.

    ``margin`` × the farthest target's bin, plus 4 bins, at least ``min_bins``, at most the
    map; the whole map when there is no target.

    Examples
    --------
    >>> shown_range_bins([(9, 64), (17, 71), (184, 114)], 512)
    234
    >>> [shown_range_bins(t, 512) for t in ([(3, 0)], [], [(500, 0)])]
    [16, 512, 512]
    """
    if not truth_bins:
        return n_range
    far = max(r for r, _ in truth_bins)
    return int(min(n_range, max(min_bins, np.ceil(far * margin) + 4)))


def detection_cells(mask: np.ndarray, other: np.ndarray | None) -> dict[str, np.ndarray]:
    """Detected cells ``(range, doppler)`` of ``mask`` by :data:`CELL_MARKERS` kind.

    With the other chain's mask, split into cells both chains detect and cells only this
    one does; without it, every cell is ``"cell"``.

    Examples
    --------
    >>> a = np.zeros((2, 3), bool); a[0, 1] = a[1, 2] = True
    >>> b = np.zeros((2, 3), bool); b[0, 1] = True
    >>> {k: v.tolist() for k, v in detection_cells(a, b).items()}
    {'both': [[0, 1]], 'only': [[1, 2]]}
    """
    if other is None:
        return {"cell": np.argwhere(mask)}
    return {"both": np.argwhere(mask & other), "only": np.argwhere(mask & ~other)}


def rd_figure(title: str, arrays, config, *, span_db: tuple[float, float] = SPAN_DB):
    """The RD-map figure (conventional, and spiking when present) as a matplotlib Figure.

    The range axis is cropped to :func:`shown_range_bins` (a little past the farthest
    target; the title counts detections beyond it); each panel marks its chain's detected
    cells (:data:`CELL_MARKERS`: with both chains, the cells both detect and the cells only
    this chain detects, in the chain's colour) and the targets (:data:`MARKERS`; a target
    whose velocity is beyond the unambiguous span is also marked *aliased*, with its true
    velocity).

    Parameters
    ----------
    title : str
        Scene name, the start of the figure's title.
    arrays : radarsnn.demo.scenes.SceneArrays
        Maps in dB (``[range, doppler]``, Doppler fftshifted), detection masks, truth bins
        (and their true velocities and aliasing, when known).
    config : radar.config.RadarConfig
        The scene's radar: gives the range (m) and velocity (m/s) of every bin.
    span_db : (float, float)
        Colour scale, dB relative to the noise floor (the conventional map's median).

    Returns
    -------
    matplotlib.figure.Figure
        One image per panel (``ax.images[0]``, its data the plotted dB re noise floor of
        the shown range bins); marker lines labelled by kind and count.
    """
    plt = _pyplot()
    panels = [("conventional", arrays.conventional_db, arrays.conventional_mask,
               arrays.spiking_mask)]
    if arrays.spiking_db is not None:
        panels.append(("spiking", arrays.spiking_db, arrays.spiking_mask,
                       arrays.conventional_mask))
    floor_db = float(np.median(arrays.conventional_db))
    range_m, velocity_mps = config.range_axis_m(), config.velocity_axis_mps()
    n_range, n_doppler = arrays.conventional_db.shape
    if (n_range, n_doppler) != (range_m.size, velocity_mps.size):
        raise ValueError(f"RD map {n_range} x {n_doppler} does not match the radar's "
                         f"{range_m.size} range bins x {velocity_mps.size} Doppler bins")
    n_show = shown_range_bins(arrays.truth_bins, n_range)
    dr_m, dv_mps = config.range_resolution_m, config.velocity_resolution_mps
    extent = [velocity_mps[0] - dv_mps / 2, velocity_mps[-1] + dv_mps / 2,
              range_m[0] - dr_m / 2, range_m[n_show - 1] + dr_m / 2]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels) + 1.2, 7.2), dpi=DPI,
                             squeeze=False, constrained_layout=True)
    image = None
    drawn = []
    aliased = [k for k, a in enumerate(getattr(arrays, "truth_aliased", []) or []) if a]
    for ax, (label, db, mask, other) in zip(axes[0], panels, strict=True):
        rel = (db - floor_db)[:n_show]
        image = ax.imshow(rel, origin="lower", aspect="auto", cmap="viridis", extent=extent,
                          vmin=span_db[0], vmax=span_db[1], interpolation="nearest")
        for kind, cells in detection_cells(mask[:n_show], None if other is None
                                           else other[:n_show]).items():
            name, marker, colour, size = CELL_MARKERS[kind]
            colour = CHAIN_COLOURS[label] if kind == "only" else colour
            ax.plot(velocity_mps[cells[:, 1]], range_m[cells[:, 0]], marker, linestyle="none",
                    color=colour, markersize=size, markeredgewidth=0.8,
                    label=f"{name.format(chain=label)} ({len(cells)})", gid=f"cells:{kind}")
        kinds = _classify(mask, db, arrays.truth_bins)
        for kind, (name, marker, colour, size) in MARKERS.items():
            rd = np.array(kinds[kind], dtype=np.int64).reshape(-1, 2)
            ax.plot(velocity_mps[rd[:, 1]], range_m[rd[:, 0]], marker, linestyle="none",
                    markerfacecolor="none", markeredgecolor=colour, markeredgewidth=1.2,
                    markersize=size, label=f"{name} ({len(rd)})")
        _mark_aliased(ax, arrays, aliased, range_m, velocity_mps, config)
        beyond = int(mask[n_show:].sum())
        n_t = len(arrays.truth_bins)
        ax.set_title(f"{label}: {len(kinds['hit'])}/{n_t} targets, "
                     f"{len(kinds['false_alarm'])} false alarms, {int(mask.sum())} cells"
                     + (f" ({beyond} beyond {range_m[n_show - 1]:.3g} m)" if beyond else ""),
                     fontsize=10)
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])  # markers beyond the shown range are clipped
        ax.set_xlabel("radial velocity (m/s)")
        ax.set_ylabel("range (m)")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2, fontsize=7.5,
                  facecolor="0.85", framealpha=1.0)
        drawn.append((ax, ax.images[0], rel))
    fig.colorbar(image, ax=list(axes[0]), extend="both",
                 label="power re noise floor (dB; floor = median of the conventional map)")
    factors = [_pool_to_pixels(fig, ax, im, rel, extent) for ax, im, rel in drawn]
    pooled = max(factors)
    note = (f"; each pixel the max of {pooled[0]} × {pooled[1]} bins" if pooled != (1, 1)
            else "")
    shown = (f"range bins 0–{n_show - 1} of {n_range}" if n_show < n_range
             else f"{n_range} range bins")
    fig.suptitle(f"{title}: range-Doppler map, {shown} × {n_doppler} Doppler bins of "
                 f"{dr_m:.3g} m × {dv_mps:.3g} m/s (unambiguous ± "
                 f"{config.max_velocity_mps:.3g} m/s){note}", fontsize=11)
    return fig


def _mark_aliased(ax, arrays, aliased: list[int], range_m, velocity_mps, config) -> None:
    """Mark each aliased target (a velocity beyond ± v_max shows at its wrapped bin)."""
    name, marker, colour, size = MARKERS_ALIASED
    true_v = getattr(arrays, "truth_velocity_mps", []) or []
    rd = np.array([arrays.truth_bins[k] for k in aliased], dtype=np.int64).reshape(-1, 2)
    ax.plot(velocity_mps[rd[:, 1]], range_m[rd[:, 0]], marker, linestyle="none",
            markerfacecolor="none", markeredgecolor=colour, markeredgewidth=1.4,
            markersize=size, label=f"{name} ({len(rd)})", gid="aliased")
    for k, (r, d) in zip(aliased, rd.tolist(), strict=True):
        text = "aliased" + (f": true {true_v[k]:+.3g} m/s" if k < len(true_v) else "")
        ax.annotate(text, (velocity_mps[d], range_m[r]), xytext=(8, 8),
                    textcoords="offset points", color=colour, fontsize=8, fontweight="bold")


def rd_maps(path: Path, title: str, arrays, config) -> Path:
    """Write :func:`rd_figure` as a PNG at ``path``; return ``path``."""
    return write_png(path, rd_figure(title, arrays, config))


def write_png(path: Path, fig) -> Path:
    """Write ``fig`` as a PNG at ``path`` atomically (whole, or the old file kept); close it."""
    png = io.BytesIO()
    fig.savefig(png, dpi=DPI, format="png")
    _pyplot().close(fig)
    write_output(path, png.getvalue(), "a figure")
    return Path(path)
