"""The demo's spike rasters: the first spike of each neuron, stage by stage, on one time axis.

For the fire-once neurons of the time-coded motifs the first spike step *is* the
raster: each neuron spikes at most once per window.  Every population with a
spike is one panel, in pipeline order, all on one shared time axis — steps
within the network's window below, microseconds above (the target's step
duration) — and each panel shows its neurons by *bin*: one axis of the
population (``range``, else ``sample``, else ``bit`` — the bit planes of a resonator's
stream code — else its last axis) on the y axis, the
other axes fixed at one index each (the first target's bin on ``doppler`` and
``range``, else the index with the most spikes), named in the panel's title.  A
population that spiked nowhere (a graded read-out sends membranes as payloads)
gets no empty panel; the figure's title lists it.

Examples
--------
>>> steps = np.full((2, 4, 3), -1); steps[1, 2, 0] = 5; steps[1, 1, 2] = 7
>>> shape = {"chirp": 2, "range": 4, "part": 3}
>>> bin_axis(shape), slice_of(steps, shape, "range", {"part": 0})
('range', ({'chirp': 1, 'part': 0}, [-1, -1, 5, -1]))
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["bin_axis", "slice_of", "spike_figure", "spike_times"]

#: Resolution of the figure and the PNG.
DPI = 110
#: The axis a panel shows its neurons along, in order of preference.
BIN_AXES = ("range", "sample", "bit")


def bin_axis(shape: dict[str, int]) -> str:
    """The axis whose bins a population's panel shows (the first of :data:`BIN_AXES`, else
    the last)."""
    return next((a for a in BIN_AXES if a in shape), list(shape)[-1])


def slice_of(steps: np.ndarray, shape: dict[str, int], axis: str,
             focus: dict[str, int]) -> tuple[dict[str, int], list[int]]:
    """The first spike steps along ``axis``, the other axes fixed: ``(fixed indices, steps)``.

    An axis in ``focus`` is fixed at that index (clipped to the axis); any other at the
    index whose slice holds the most spikes (the first on a tie).
    """
    cube = np.asarray(steps).reshape(tuple(shape.values()))
    names = list(shape)
    fixed: dict[str, int] = {}
    for name in list(shape):
        if name == axis:
            continue
        k = names.index(name)
        if name in focus:
            fixed[name] = int(min(max(focus[name], 0), shape[name] - 1))
        else:
            others = tuple(j for j in range(cube.ndim) if j != k)
            fixed[name] = int(np.argmax((cube >= 0).sum(axis=others)))
        cube = np.take(cube, fixed[name], axis=k)
        names.pop(k)
    return fixed, cube.reshape(-1).tolist()


def spike_figure(title: str, first_spikes: dict[str, np.ndarray],
                 shapes: dict[str, dict[str, int]] | None = None, *, step_s: float | None = None,
                 focus: dict[str, int] | None = None, max_bins: int | None = None,
                 max_panels: int = 8):
    """First spike steps of the chain's populations (frame 0), one panel each, in pipeline order.

    Parameters
    ----------
    title : str
        Scene name, the start of the figure's title.
    first_spikes : dict of str to ndarray
        Population id (``node/role``) -> first spike step per neuron (flat, -1: none),
        in pipeline order (the order of the stages through the chain).
    shapes : dict of str to dict, optional
        Population id -> its named axes (``Population.shape``); without it a population
        is one axis ``neuron``.
    step_s : float, optional
        Duration of a time step (the target's ``time_step_s``): the µs axis on top.
    focus : dict of str to int, optional
        Axis -> index a panel fixes that axis at (e.g. the first target's ``range`` and
        ``doppler`` bins).
    max_bins : int, optional
        Show at most this many bins of the ``range`` axis (the RD figure's shown range).
    max_panels : int
        At most this many populations with spikes (the first ones) are drawn.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per drawn population, titled ``<population id>: ...``, sharing the time
        axis; neuron and step ticks at integers.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    shapes = shapes or {}
    active = [(p, s) for p, s in first_spikes.items() if np.any(np.asarray(s) >= 0)]
    silent = [p for p in first_spikes if p not in dict(active)]
    items = active[:max_panels]
    n = max(1, len(items))
    last = max((int(np.max(s)) for _, s in items), default=1)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.6 * n + 1.3), squeeze=False, sharex=True)
    for ax, (pid, steps) in zip(axes[:, 0], items, strict=False):
        shape = shapes.get(pid) or {"neuron": int(np.size(steps))}
        axis = bin_axis(shape)
        fixed, line = slice_of(steps, shape, axis, focus or {})
        line = np.array(line)
        if axis == "range" and max_bins:
            line = line[:max_bins]
        fired = np.flatnonzero(line >= 0)
        ax.plot(line[fired], fired, "|", markersize=4, color="black")
        ax.set_ylim(-0.5, max(line.size, 1) - 0.5)
        ax.yaxis.set_major_locator(MaxNLocator(nbins=4, integer=True))
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel(f"{axis} bin", fontsize=8)
        where = ", ".join(f"{a} {i}" for a, i in fixed.items())
        total = int((np.asarray(steps) >= 0).sum())
        ax.set_title(f"{pid}: {axis} bins 0–{line.size - 1}" + (f" at {where}" if where else "")
                     + f"; {fired.size} spiked here, {total} of {np.size(steps)} in all",
                     fontsize=8.5)
    axes[-1, 0].set_xlim(-0.5, last + 1.5)
    axes[-1, 0].set_xlabel("time step within the network's window")
    if step_s:
        top = axes[0, 0].secondary_xaxis(
            "top", functions=(lambda s: s * step_s * 1e6, lambda us: us / (step_s * 1e6)))
        top.set_xlabel(f"µs (steps of {step_s * 1e6:g} µs)", fontsize=8)
    note = f"; no spike time (graded read-out or silent): {', '.join(silent)}" if silent else ""
    fig.suptitle(f"{title}: first spike per neuron (frame 0), stages in pipeline order{note}",
                 fontsize=9.5, wrap=True)
    fig.tight_layout()
    return fig


def spike_times(path: Path, title: str, first_spikes: dict[str, np.ndarray],
                shapes: dict[str, dict[str, int]] | None = None, **options) -> Path:
    """Write :func:`spike_figure` as a PNG at ``path`` atomically; return ``path``."""
    from radarsnn.demo.figures import write_png

    return write_png(path, spike_figure(title, first_spikes, shapes, **options))
