"""The core map of a resource report: every core, coloured by the stages placed on it.

Cores are drawn in rows (at most 32 a row, a chip's cores per row when it has
fewer), numbered left to right.  Each core is a light grey square (its
capacity) filled from the bottom up to its utilisation (the largest of the
budgets: neurons, input axons, output axons, synapse memory) in the colour of
its stage; a core shared by several stages is split into side-by-side stripes,
one per stage, so a stage that only shares cores is still seen.  A used core is
filled to at least :data:`MIN_FILL` so that a lightly used one stays visible.
The legend lists every stage in pipeline order (the report's stage order) with
its core count, in exactly the colour of its patches.

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
"""

from __future__ import annotations

__all__ = ["MIN_FILL", "core_map_figure", "core_stages", "stage_colours", "stage_order"]

#: Smallest fill height of a used core (fraction of the square).
MIN_FILL = 0.1
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
        Its stage patches carry ``gid = "stage:<name>"`` (core outlines ``"core"``).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle

    cores = data["cores"]
    per_row = max(1, min(32, data.get("cores_per_chip") or 32))
    n_rows = max(1, -(-len(cores) // per_row))
    stages = stage_order(data)
    colour = stage_colours(stages)
    count = {s: 0 for s in stages}
    fig, ax = plt.subplots(figsize=(max(4.0, per_row * 0.3), max(2.0, n_rows * 0.3 + 1.0)))
    for c in cores:
        i = int(c["core"])
        x, y = i % per_row, -(i // per_row)
        ax.add_patch(Rectangle((x, y), _SIZE, _SIZE, facecolor="0.92", edgecolor="0.6",
                               linewidth=0.5, gid="core"))
        on = core_stages(c)
        util = max(c.get("utilisation") or [1.0])
        height = _SIZE * min(1.0, max(MIN_FILL, util))
        width = _SIZE / len(on)
        for k, s in enumerate(on):
            count[s] += 1
            ax.add_patch(Rectangle((x + k * width, y), width, height, facecolor=colour[s],
                                   edgecolor="none", gid=f"stage:{s}"))
    ax.set_xlim(-0.1, per_row)
    ax.set_ylim(-n_rows + 1 - 0.1, 1)
    ax.set_aspect("equal")
    ax.axis("off")
    shared = sum(len(core_stages(c)) > 1 for c in cores)
    ax.set_title(f"{data['chain']} on {data['target']}: {len(cores)} cores"
                 + (f" ({shared} shared by several stages)" if shared else "")
                 + "; fill height = utilisation (max over budgets)", fontsize=9)
    if stages:
        handles = [Patch(facecolor=colour[s], edgecolor="none",
                         label=f"{s} ({count[s]} core{'s' if count[s] != 1 else ''})")
                   for s in stages]
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)
    return fig
