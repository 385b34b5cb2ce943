"""Figures of a sweep's summary rows (matplotlib, Agg backend, PNG files).

* ``fig7`` — Vogginger et al.'s Fig. 7: CFAR sensitivity and precision vs time steps,
  one panel per variant (every grid axis other than ``x`` that varies);
* ``sft_rmse`` — S-FT RMSE vs time steps, one line per variant (e.g. policy);
* ``weight_bits`` — a metric vs weight bits, one line per variant;
* ``pareto`` — a metric vs a cost column over all points, the Pareto-optimal
  points (no other point is at least as cheap and at least as accurate, one of
  the two strictly) joined by a line.  When the figure's cost is the same at
  every point (e.g. ``synapses`` over a ``time_steps`` grid) it is plotted
  against the first cost that varies (:func:`pick_cost`), and says so.

Examples
--------
>>> pareto_front([3, 1, 2, 2], [0.9, 0.5, 0.7, 0.95])
[1, 3]
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from ir.errors import CompileError
from radarsnn.cli.chain import write_output
from radarsnn.sweep.sections import FigureSpec

__all__ = ["pareto_front", "pick_cost", "draw_figures", "MAIN_FIELD"]

#: The field a metric is plotted by when a figure names only the metric key.
MAIN_FIELD = {"cfar": "sensitivity", "detection": "pd", "sft_rmse": "rmse",
              "classifier_accuracy": "accuracy"}
#: Metric whose value is better when smaller (the Pareto front minimises it).
LOWER_IS_BETTER = {"rmse", "false_alarms_per_frame"}


def pareto_front(cost: Any, value: Any, *, maximize: bool = True) -> list[int]:
    """Indices of the Pareto-optimal points, by increasing cost.

    A point is optimal when no other has ``cost <=`` and ``value >=`` (``<=`` when
    ``maximize`` is False) with one of them strict.  Sorting by (cost, best value
    first) and keeping each point that beats every cheaper one is O(n log n).
    """
    c = np.asarray(cost, np.float64)
    v = np.asarray(value, np.float64) * (1.0 if maximize else -1.0)
    order = np.lexsort((-v, c))
    best = np.maximum.accumulate(v[order])
    keep = np.r_[True, v[order][1:] > best[:-1]]
    return [int(i) for i in order[keep]]


def _resolve(fig: FigureSpec, names: dict[str, str], default_name: str | None) -> tuple[str, str]:
    """``(metric key, field)`` of a figure."""
    if fig.metric:
        key, _, fld = fig.metric.partition(".")
    else:
        keys = [k for k, n in names.items() if default_name in (None, n)]
        if not keys:
            raise CompileError(f"figure {fig.kind!r}: the sweep has no {default_name or 'any'} "
                               f"metric (metrics {sorted(names)}); add one or set `metric`")
        key, fld = keys[0], ""
    if key not in names:
        raise CompileError(f"figure {fig.kind!r}: metric {key!r} is not in the sweep's metrics "
                           f"{sorted(names)}")
    return key, fld or MAIN_FIELD.get(names[key], "")


def _variants(rows: list[dict], x: str) -> dict[str, list[dict]]:
    varying = [k for k in rows[0]["params"]
               if k != x and len({repr(r["params"].get(k)) for r in rows}) > 1]
    groups: dict[str, list[dict]] = {}
    for r in rows:
        label = ", ".join(f"{k}={r['params'].get(k)}" for k in varying or ["chain"])
        groups.setdefault(label, []).append(r)
    return groups


def _series(rows: list[dict], x: str, key: str, fld: str) -> tuple[list, list]:
    pts = sorted((r["params"][x], r["metrics"][key][fld]) for r in rows
                 if x in r["params"] and key in r["metrics"] and r["params"][x] is not None)
    return [p[0] for p in pts], [p[1] for p in pts]


def _log_x(ax, rows: list[dict], x: str) -> None:
    """A log x axis labelled at the grid's own values (10, 20, 50, …)."""
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    ax.set_xscale("log")
    ax.set_xticks(sorted({r["params"][x] for r in rows if r["params"].get(x) is not None}))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.tick_params(axis="x", labelsize="small", labelrotation=45)


def _fig7(plt, rows, fig, names):
    key, _ = _resolve(fig, names, "cfar")
    x = fig.x or "time_steps"
    groups = _variants(rows, x)
    f, axes = plt.subplots(1, len(groups), figsize=(4.2 * len(groups), 3.4), squeeze=False)
    for ax, (label, group) in zip(axes[0], groups.items(), strict=True):
        for fld, style in (("sensitivity", "o-"), ("precision", "s--")):
            xs, ys = _series(group, x, key, fld)
            ax.plot(xs, 100 * np.asarray(ys), style, label=fld)
        ax.set(xlabel=x.replace("_", " "), ylabel="%", title=label)
        _log_x(ax, group, x)
        ax.grid(alpha=0.3)
        ax.legend()
    return f


def _lines(plt, rows, fig, names, default_name, x_default):
    key, fld = _resolve(fig, names, default_name)
    x = fig.x or x_default
    f, ax = plt.subplots(figsize=(5.5, 3.8))
    for label, group in _variants(rows, x).items():
        xs, ys = _series(group, x, key, fld)
        ax.plot(xs, ys, "o-", label=label)
    ax.set(xlabel=x.replace("_", " "), ylabel=f"{key}.{fld}")
    if x == "time_steps":
        _log_x(ax, rows, x)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    return f


#: Cost columns tried, in this order, when the figure's cost is the same at every point.
COST_FALLBACK = ("synapses", "neurons", "cores", "steps", "synaptic_events_per_frame",
                 "spikes_per_frame")
#: Axis labels of the cost columns.
COST_LABELS = {"neurons": "neurons", "inputs": "input neurons",
               "synapses": "synapses (instances wired)", "synapses_stored": "synapses stored",
               "steps": "time steps per frame", "cores": "cores",
               "spikes_per_frame": "spikes per frame",
               "synaptic_events_per_frame": "synaptic events per frame"}


def _cost_values(rows: list[dict], key: str, cost: str) -> tuple[list[dict], list[float]]:
    ok = [r for r in rows if key in r["metrics"] and r["cost"].get(cost) is not None]
    return ok, [float(r["cost"][cost]) for r in ok]


def pick_cost(rows: list[dict], key: str, cost: str) -> tuple[str, str | None]:
    """The cost column to plot and, when it is not ``cost``, why.

    ``cost`` when it varies over the points with metric ``key``; else the first
    of :data:`COST_FALLBACK` that does (the note names the constant one); else
    ``cost`` with a note that every point costs the same.

    Examples
    --------
    >>> rows = [{"metrics": {"m": {}}, "cost": {"synapses": 5, "steps": s}} for s in (16, 64)]
    >>> pick_cost(rows, "m", "synapses")
    ('steps', 'cost.synapses is 5 at every point: plotted against cost.steps')
    >>> pick_cost(rows[:1], "m", "synapses")[1]
    'cost.synapses is 5 at every point, and so is every other cost: no trade-off to show'
    """
    ok, values = _cost_values(rows, key, cost)
    if len(set(values)) > 1:
        return cost, None
    if values:
        value = f"{int(values[0]):,}" if values[0].is_integer() else f"{values[0]:g}"
        same = f"cost.{cost} is {value} at every point"
    else:
        same = f"no point has cost.{cost}"
    for other in COST_FALLBACK:
        if other != cost and len(set(_cost_values(rows, key, other)[1])) > 1:
            return other, f"{same}: plotted against cost.{other}"
    return cost, f"{same}, and so is every other cost: no trade-off to show"


def _pareto(plt, rows, fig, names):
    key, fld = _resolve(fig, names, None)
    cost, note = pick_cost(rows, key, fig.cost or "synapses")
    ok, c = _cost_values(rows, key, cost)
    v = [r["metrics"][key][fld] for r in ok]
    front = pareto_front(c, v, maximize=fld not in LOWER_IS_BETTER)
    f, ax = plt.subplots(figsize=(5.5, 3.8 + (0.3 if note else 0.0)))
    ax.scatter(c, v, color="0.6", label="points")
    ax.plot([c[i] for i in front], [v[i] for i in front], "o-", color="C3", label="Pareto front")
    if len(set(c)) > 1 and max(c) / max(min(c), 1e-300) >= 20:
        ax.set_xscale("log")
    ax.set(xlabel=f"{COST_LABELS.get(cost, cost)} (cost.{cost})", ylabel=f"{key}.{fld}")
    if note:
        ax.set_title(note, fontsize=8, color="C3" if "no trade-off" in note else "0.2")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    return f


def draw_figures(figures: list[FigureSpec], rows: list[dict], out_dir: str | Path,
                 names: dict[str, str] | None = None) -> list[Path]:
    """Draw each figure of ``figures`` from the summary ``rows``; return the PNG paths.

    Parameters
    ----------
    figures : list of FigureSpec
        The spec's ``figures``.
    rows : list of dict
        :func:`radarsnn.sweep.results.summarize` rows (incomplete or failed rows skipped).
    out_dir : str or Path
        Folder of the PNG files (created), one ``<name or kind>.png`` per figure, each
        written atomically (whole, or the previous one kept).
    names : dict, optional
        Metric key -> registered metric name (default: each key is its name).

    Raises
    ------
    CompileError
        A figure names a metric the sweep does not have, or its file would be written
        outside ``out_dir``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in rows if r["complete"] and not r["error"] and r["metrics"]]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not rows:
        return []
    names = names or {k: k for k in rows[0]["metrics"]}
    drawers = {
        "fig7": lambda fig: _fig7(plt, rows, fig, names),
        "sft_rmse": lambda fig: _lines(plt, rows, fig, names, "sft_rmse", "time_steps"),
        "weight_bits": lambda fig: _lines(plt, rows, fig, names, None, "weight_bits"),
        "pareto": lambda fig: _pareto(plt, rows, fig, names),
    }
    paths = []
    for fig in figures:
        path = _inside(out, fig.file_name)
        f = drawers[fig.kind](fig)
        f.tight_layout()
        png = io.BytesIO()
        f.savefig(png, dpi=110, format="png")
        plt.close(f)
        write_output(path, png.getvalue(), f"figure {fig.file_name!r}")
        paths.append(path)
    return paths


def _inside(folder: Path, name: str) -> Path:
    """``folder/name``, refused unless it is a file directly in ``folder``.

    Examples
    --------
    >>> _inside(Path("out"), "../x.png")
    Traceback (most recent call last):
    ir.errors.CompileError: figure file '../x.png' would be written outside out; give the \
figure a plain `name` (no folder)
    """
    path = folder / name
    if os.path.dirname(name) or os.path.isabs(name) or path.resolve().parent != folder.resolve():
        raise CompileError(f"figure file {name!r} would be written outside {folder}; give the "
                           "figure a plain `name` (no folder)")
    return path
