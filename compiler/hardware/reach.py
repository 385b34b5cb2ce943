r"""Fan-in lines of blocks: the distinct source neurons with a synapse into each block.

For a block ``B`` of population ``T`` and a source population ``S`` the reached
set is :math:`\{ j \in S : \exists\, t \in B,\ \text{synapse } j \to t \}` over
every projection ``S → T`` (two projections reaching one neuron count once).  A
matrix projection reaches, from target :math:`(r, p)` (repetition coordinates
``r``, column ``p``), the sources :math:`(r, c)` with :math:`W_{cp} \ne 0`; a
stencil reaches :math:`x + o` for every non-zero tap ``o`` (wrapped, or dropped
beyond a ``clip`` edge).

The sweep enumerates, per chunk of whole blocks, the reached ``(block, source)``
pairs — for a matrix by one sparse product of the distinct ``(block, r)`` pairs'
column indicator with :math:`[W \ne 0]^T`, which gives each pair once — and, for a
source reached by a stencil or by several projections, marks them in a boolean
``(blocks × source neurons)`` matrix per group of blocks (bounded memory).

Examples
--------
>>> from compiler.hardware.blocks import Blocks
>>> from compiler.snn import MatrixProjection, Population, SpikingNetwork
>>> net = SpikingNetwork(name="t", n_steps=4, populations=[
...     Population(id="x", shape={"rep": 2, "i": 3}, source=True),
...     Population(id="y", shape={"rep": 2, "o": 2})],
...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
...                                   produce=("o",), weights=np.array([[1., 0], [1, 0], [0, 1]]))])
>>> fan_in, reach = reach_sweep(net, "y", Blocks.uniform("y", 4, 2))
>>> blk, src = reach["x"]
>>> fan_in.tolist(), sorted(zip(blk.tolist(), src.tolist()))
([3, 3], [(0, 0), (0, 1), (0, 2), (1, 3), (1, 4), (1, 5)])
"""

from __future__ import annotations

import numpy as np

from compiler.hardware.blocks import Blocks
from compiler.hardware.projection_info import ProjectionInfo, projection_info
from compiler.snn import Population, SpikingNetwork

__all__ = ["reach_sweep", "sweep_infos"]

_CHUNK = 1 << 21          # neuron x tap pairs handled at once
_MARK_LIMIT = 1 << 25     # booleans in one (blocks x source neurons) mark matrix


def _chunks(edges: np.ndarray, g0: int, g1: int, step: int) -> list[tuple[int, int]]:
    """Runs ``[b0, b1)`` of whole blocks of ``g0 … g1-1``, each of about ``step`` neurons."""
    cuts = np.arange(int(edges[g0]), int(edges[g1]), step)
    first = np.unique(np.searchsorted(edges, cuts, side="right") - 1)
    bounds = np.concatenate([first, [g1]]).tolist()
    return [(b0, b1) for b0, b1 in zip(bounds[:-1], bounds[1:], strict=True) if b1 > b0]


def reach_sweep(network: SpikingNetwork, population: str, blocks: Blocks
                ) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Fan-in lines of every block of ``population`` and the reached pairs.

    Parameters
    ----------
    network : SpikingNetwork
        The (validated) network.
    population : str
        A neuron population.
    blocks : Blocks
        Its blocks.

    Returns
    -------
    fan_in : ndarray of int64, shape (n_blocks,)
        Distinct reached source neurons per block, summed over source populations.
    reach : dict of str to (ndarray, ndarray)
        Per source population: the distinct ``(block, source flat index)`` pairs
        (in no particular order).
    """
    pops = network.population
    tgt = pops[population]
    infos = [projection_info(p, pops[p.source], tgt) for p in network.incoming(population)]
    return sweep_infos(pops, tgt, infos, blocks)


def sweep_infos(pops: dict[str, Population], tgt: Population, infos: list[ProjectionInfo],
                blocks: Blocks) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """:func:`reach_sweep` from the precomputed infos of the projections into ``tgt``."""
    by_source: dict[str, list[ProjectionInfo]] = {}
    for info in infos:
        by_source.setdefault(info.proj.source, []).append(info)
    edges, nb = blocks.edges, blocks.n_blocks
    fan_in = np.zeros(nb, np.int64)
    pairs: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {s: [] for s in by_source}
    # a source reached by one matrix only gets distinct (block, source) pairs from chunks of
    # whole blocks (distinct (block, r) rows, distinct columns c per row); others are marked
    marked = [s for s, v in by_source.items() if len(v) > 1 or not v[0].shared_matrix]
    biggest = max((pops[s].size for s in marked), default=1)
    per_group = max(1, _MARK_LIMIT // biggest) if marked else max(nb, 1)
    taps = max([i.reach_taps for v in by_source.values() for i in v] + [1])
    step = max(1, _CHUNK // taps)
    for g0 in range(0, nb, per_group):
        g1 = min(nb, g0 + per_group)
        marks = {s: np.zeros((g1 - g0, pops[s].size), bool) for s in marked}
        for b0, b1 in _chunks(edges, g0, g1, step):
            pos = np.arange(int(edges[b0]), int(edges[b1]), dtype=np.int64)
            flat, blk = blocks.flat(pos), blocks.block_of(pos)
            for s, infos in by_source.items():
                for info in infos:
                    rows, cols = info.reached(pops[s], tgt, flat, blk)
                    if s in marks:
                        marks[s][rows - g0, cols] = True
                    else:
                        fan_in += np.bincount(rows, minlength=nb)
                        pairs[s].append((rows, cols))
        for s, m in marks.items():
            fan_in[g0:g1] += m.sum(axis=1)
            r, c = np.nonzero(m)
            pairs[s].append((r + g0, c))
    reach = {s: (np.concatenate([p[0] for p in v]), np.concatenate([p[1] for p in v]))
             for s, v in pairs.items() if v}
    return fan_in, reach
