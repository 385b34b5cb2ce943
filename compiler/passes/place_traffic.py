r"""Block affinity and spike traffic of a placement (the ``place`` pass).

The **affinity** of two blocks is the number of distinct (source neuron, target
block) pairs between them, in both directions; the greedy placer keeps such
blocks together.  **Traffic** per frame, with :math:`\hat s_S` spikes per neuron of
population ``S``:

.. math:: \text{messages} = \sum_{(c, j)} \hat s_{S(j)}\,[\text{core}(j) \ne c]

over the distinct pairs (destination core ``c``, source neuron ``j`` with a
synapse onto ``c``), counted :math:`R` times into the blocks of a stage
multiplexed :math:`R` times; messages from spike sources are ``host_input``, those
across a multiplexed stage's boundary ``buffered``, the others ``inter_core``, of
which those crossing chips are ``inter_chip``.

Both read the reached ``(block, source neuron)`` pairs of every
:class:`~compiler.hardware.Demand`; ``offsets[k][pid]`` is the index of the first
block of population ``pid`` of network ``k`` among all placed blocks.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from compiler.hardware.intsets import unique_keys

__all__ = ["block_affinity", "core_messages", "spike_traffic"]

def block_affinity(splits, offsets) -> sp.csr_matrix:
    """Symmetric ``(blocks × blocks)`` affinity of the placed blocks of all ``splits``."""
    rows, cols = [], []
    for k, rec in enumerate(splits):
        for tgt, dem in rec.demand.items():
            for src, (blk, neuron) in dem.reach.items():
                if not rec.on_chip(src, tgt):
                    continue
                rows.append(offsets[k][tgt] + blk)
                cols.append(offsets[k][src] + rec.demand[src].blocks.block_of_neuron(neuron))
    n = max((o[p] + d.blocks.n_blocks for o, r in zip(offsets, splits, strict=True)
             for p, d in r.demand.items()), default=0)
    if not rows:
        return sp.csr_matrix((n, n))
    r, c = np.concatenate(rows), np.concatenate(cols)
    m = sp.coo_matrix((np.ones(r.size), (r, c)), shape=(n, n)).tocsr()
    m = m + m.T
    m.setdiag(0)
    m.eliminate_zeros()
    return m


def spike_traffic(networks, splits, offsets, core, cores_per_chip, spikes, *,
                  memo=None) -> dict:
    """Messages per frame of the placement ``core`` (see the module docstring).

    With ``memo`` (:class:`compiler.memo.CompileMemo`) a network's terms are counted once
    per network, split record, block offsets, cores of its blocks and spike rates; they
    are added in the same order either way, so the sums are the same to the bit.
    """
    sums = {"host_input": 0.0, "inter_core": 0.0, "inter_chip": 0.0, "buffered": 0.0}
    for k, (net, rec) in enumerate(zip(networks, splits, strict=True)):
        def count(net=net, rec=rec, k=k):
            return _network_terms(net, rec, offsets[k], core, cores_per_chip, spikes[k])
        if memo is None or not offsets[k]:
            terms = count()
        else:
            lo = min(offsets[k].values())
            hi = max(offsets[k][p] + d.blocks.n_blocks for p, d in rec.demand.items())
            key = (tuple(offsets[k].items()), core[lo:hi].tobytes(), cores_per_chip,
                   tuple(spikes[k].items()))
            terms = memo.kept("traffic", (net, rec), key, count)
        for name, value in terms:  # in the order the pairs were visited
            sums[name] += value
    missing = sorted({f"{networks[k].name}/{pid}" for k, rec in enumerate(splits)
                      for pid, dem in rec.demand.items()
                      if networks[k].incoming(pid) and not dem.reach})
    return {**sums, "not_counted": missing}


def _network_terms(net, rec, offsets, core, cores_per_chip, spikes) -> list[tuple[str, float]]:
    """The messages of one network's reached pairs, as ``(sum name, amount)`` in the order
    :func:`spike_traffic` adds them."""
    pops, out = net.population, []
    for tgt, dem in rec.demand.items():
        for src, (blk, neuron) in dem.reach.items():
            dst = core[offsets[tgt] + blk]
            keys = unique_keys(dst * pops[src].size + neuron)
            dst, neuron = keys // pops[src].size, keys % pops[src].size
            rate = spikes.get(src, 0.0) * rec.runs(tgt)
            if src not in rec.demand:
                out.append(("host_input", rate * dst.size))
                continue
            if not rec.on_chip(src, tgt):
                out.append(("buffered", rate * dst.size))
                continue
            home = core[offsets[src] + rec.demand[src].blocks.block_of_neuron(neuron)]
            away = home != dst
            out.append(("inter_core", rate * int(away.sum())))
            if cores_per_chip:
                out.append(("inter_chip", rate * int((away & (home // cores_per_chip
                                                              != dst // cores_per_chip)).sum())))
    return out


def core_messages(networks, splits, offsets, core, spikes) -> list[sp.csr_matrix]:
    """Per network, the ``(cores × cores)`` messages per frame between cores of the placement.

    Entry ``[a, b]`` sums, over the distinct pairs (destination core ``b``, source neuron on
    core ``a ≠ b``), the source's spikes per frame (× the target's runs): the ``inter_core``
    messages of :func:`spike_traffic` by source and destination core (host input and
    buffered messages excluded).  Summing the entries whose cores lie on different chips
    gives ``inter_chip``.

    Examples
    --------
    >>> core_messages([], [], [], np.zeros(0, np.int64), [])
    []
    """
    n = int(core.max()) + 1 if core.size else 0
    out = []
    for k, (net, rec) in enumerate(zip(networks, splits, strict=True)):
        pops = net.population
        rows, cols, vals = [], [], []
        for tgt, dem in rec.demand.items():
            for src, (blk, neuron) in dem.reach.items():
                if src not in rec.demand or not rec.on_chip(src, tgt):
                    continue
                dst = core[offsets[k][tgt] + blk]
                keys = unique_keys(dst * pops[src].size + neuron)
                dst, neuron = keys // pops[src].size, keys % pops[src].size
                home = core[offsets[k][src] + rec.demand[src].blocks.block_of_neuron(neuron)]
                away = home != dst
                rows.append(home[away])
                cols.append(dst[away])
                vals.append(np.full(int(away.sum()), spikes[k].get(src, 0.0) * rec.runs(tgt)))
        if rows:
            m = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                              shape=(n, n)).tocsr()
        else:
            m = sp.csr_matrix((n, n))
        out.append(m)
    return out
