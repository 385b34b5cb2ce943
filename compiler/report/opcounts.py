r"""Operations per cell under test (Vogginger et al.'s Table 1): conventional vs spiking CFAR.

With :math:`N` training cells and :math:`T` time steps:

==================  ===============  ==========
algorithm           ADD              CMP
==================  ===============  ==========
OS-CFAR             0                N + 1
OS-CFAR (spiking)   N                T
CA-CFAR             N                1
CA-CFAR (spiking)   N + T            T
==================  ===============  ==========

(an ADD of the spiking rows is a synaptic event or a ramp increment, a CMP a
threshold check per step; releasing the input spikes is not counted).

Examples
--------
>>> [r["total"] for r in cfar_op_counts("os", 176, 100)]
[177, 276]
>>> [r["total"] for r in cfar_op_counts("ca", 176, 500)]
[177, 1176]
"""

from __future__ import annotations

from ir import Graph

__all__ = ["cfar_op_counts", "graph_cfar_op_counts"]


def cfar_op_counts(kind: str, n_train: int, n_steps: int) -> list[dict]:
    """The conventional and the spiking row of Table 1 for one CFAR kind (``"os"``/``"ca"``)."""
    if kind == "os":
        conv, spk = (0, n_train + 1), (n_train, n_steps)
    else:
        conv, spk = (n_train, 1), (n_train + n_steps, n_steps)
    name = f"{kind.upper()}-CFAR"
    return [{"algorithm": name, "add": conv[0], "cmp": conv[1], "total": sum(conv)},
            {"algorithm": f"{name} (spiking)", "add": spk[0], "cmp": spk[1], "total": sum(spk),
             "n_steps": n_steps}]


def graph_cfar_op_counts(graph: Graph, n_steps: dict[str, int]) -> list[dict]:
    """Table 1 rows for every ``cfar`` node, with ``n_steps[node]`` time steps.

    Examples
    --------
    >>> from pathlib import Path
    >>> g = Graph.from_yaml(Path("examples/chains/carrada_rd_oscfar.yaml"))
    >>> [(r["node"], r["total"]) for r in graph_cfar_op_counts(g, {"det": 100})]
    [('det', 177), ('det', 276)]
    """
    types = graph.infer_types()
    rows = []
    for nid in graph.topological_order():
        op = graph.op(nid)
        if op.op != "cfar" or nid not in n_steps:
            continue
        (src,) = graph.inputs_of(nid)
        n_train = op.window(nid, types[src]).n_train
        rows += [{"node": nid, "n_train": n_train, **r}
                 for r in cfar_op_counts(op.kind, n_train, n_steps[nid])]
    return rows
