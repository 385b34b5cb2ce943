"""The core map of a resource report: every core, its utilisation and the stages on it.

Cores are drawn in rows (at most 32 a row, a chip's cores per row when it has
fewer), numbered left to right; each row is labelled with its chip and its first
and last core, and the columns with the core offset in the row.  Each core is a
square filled in the colour of its utilisation (the largest of its budgets:
neurons, input axons, output axons, synapse memory) on one colour scale from 0 to
100 % (the colour bar), with a stripe along its bottom in the colour of its stage;
a core shared by several stages has one stripe piece per stage, so a stage that
only shares cores is still seen.  The legend lists every stage in pipeline order
(the report's stage order) with its core count, in exactly the colour of its
stripes.

Examples
--------
>>> data = {"chain": "c", "target": "t", "cores_per_chip": 4, "stages": [{"node": "b"}],
...         "cores": [{"core": 0, "stages": ["a", "b"], "utilisation": [0.5]},
...               {"core": 1, "stage": "b", "utilisation": [1.0]}]}
>>> stage_order(data)
['b', 'a']
>>> fig = core_map_figure(data)
>>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
['b (2 cores)', 'a (1 core)']
>>> [round(p.get_facecolor()[0], 3) for p in fig.axes[0].patches if p.get_gid() == "core"]
[0.128, 0.993]
"""

from __future__ import annotations

__all__ = ["STRIPE", "UTILISATION_CMAP", "core_map_figure", "core_stages", "stage_colours",
           "stage_order"]

#: Height of the stage stripe along a core's bottom (fraction of the square).
STRIPE = 0.28
#: The colour scale of the utilisation (0 to 1).
UTILISATION_CMAP = "viridis"
_SIZE = 0.9  # side of a core's square (cores are 1 apart)


def core_stages(core: dict) -> list[str]:
    """The stages placed on ``core``: its ``stages`` list, else its one ``stage``."""
    return list(core.get("stages") or [core.get("stage", "?")])


def stage_order(data: dict) -> list[str]:
    """Stages on the cores in pipeline order: the report's stage rows first, then the rest."""
    on_cores = [s for c in data["cores"] for s in core_stages(c)]
    rows = [r["node"] for r in data.get("stages", [])]
    ordered = list(dict.fromkeys(s for s in rows if s in on_cores))
    return ordered + [s for s in dict.fromkeys(on_cores) if s not in ordered]


def stage_colours(stages: list[str]) -> dict[str, tuple]:
    """One distinct RGBA colour per stage (tab10; tab20 past 10 stages, hues past 20)."""
    import matplotlib

    n = len(stages)
    if n <= 10:
        colours = [matplotlib.colormaps["tab10"](k) for k in range(n)]
    elif n <= 20:
        colours = [matplotlib.colormaps["tab20"](k) for k in range(n)]
    else:
        colours = [matplotlib.colormaps["hsv"](k / n) for k in range(n)]
    return dict(zip(stages, colours, strict=True))


def core_map_figure(data: dict):
    """Draw the cores of a report's ``data`` (schema of :mod:`compiler.report.render`).

    Returns
    -------
    matplotlib.figure.Figure
        Its core squares carry ``gid = "core"`` (coloured by utilisation), the stage
        stripes ``gid = "stage:<name>"``; ``fig.axes[1]`` is the utilisation colour bar.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.patches import Patch, Rectangle

    cores = data["cores"]
    per_chip = data.get("cores_per_chip") or 0
    per_row = max(1, min(32, per_chip or 32))
    n_rows = max(1, -(-(max((int(c["core"]) for c in cores), default=0) + 1) // per_row))
    stages = stage_order(data)
    colour = stage_colours(stages)
    count = {s: 0 for s in stages}
    norm, cmap = Normalize(0.0, 1.0), matplotlib.colormaps[UTILISATION_CMAP]
    fig, ax = plt.subplots(figsize=(max(5.0, per_row * 0.32 + 3.5), max(2.2, n_rows * 0.34 + 1.4)))
    utils = []
    for c in cores:
        i = int(c["core"])
        x, y = i % per_row, -(i // per_row)
        util = min(1.0, max(c.get("utilisation") or [0.0]))
        utils.append(util)
        ax.add_patch(Rectangle((x, y), _SIZE, _SIZE, facecolor=cmap(norm(util)), edgecolor="0.4",
                               linewidth=0.5, gid="core"))
        on = core_stages(c)
        width = _SIZE / len(on)
        for k, s in enumerate(on):
            count[s] += 1
            ax.add_patch(Rectangle((x + k * width, y), width, _SIZE * STRIPE, facecolor=colour[s],
                                   edgecolor="none", gid=f"stage:{s}"))
    for row in range(n_rows):
        first = row * per_row
        last = min(first + per_row, max(len(cores), first + 1)) - 1
        chip = f"chip {first // per_chip}, " if per_chip else ""
        ax.text(-0.3, -row + _SIZE / 2, f"{chip}cores {first}–{last}", ha="right", va="center",
                fontsize=7)
    for col in range(0, per_row, 4 if per_row > 8 else 1):
        ax.text(col + _SIZE / 2, 1.05, f"+{col}", ha="center", va="bottom", fontsize=6,
                color="0.3")
    ax.set_xlim(-0.1, per_row)
    ax.set_ylim(-n_rows + 1 - 0.1, 1.4)
    ax.set_aspect("equal")
    ax.axis("off")
    shared = sum(len(core_stages(c)) > 1 for c in cores)
    mean = sum(utils) / len(utils) if utils else 0.0
    ax.set_title(f"{data['chain']} on {data['target']}: {len(cores)} cores"
                 + (f" ({shared} shared by several stages)" if shared else "")
                 + f"; utilisation (largest budget) mean {mean:.0%}, colour below; "
                 "stripe = stage", fontsize=9)
    fig.colorbar(ScalarMappable(norm, cmap), ax=ax, orientation="horizontal", fraction=0.08,
                 pad=0.02, aspect=40, label="core utilisation (largest budget: neurons, axons, "
                                            "synapse memory)",
                 format=matplotlib.ticker.PercentFormatter(1.0))
    if stages:
        handles = [Patch(facecolor=colour[s], edgecolor="none",
                         label=f"{s} ({count[s]} core{'s' if count[s] != 1 else ''})")
                   for s in stages]
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7,
                  title="stage (stripe)", title_fontsize=7)
    return fig
