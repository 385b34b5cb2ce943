r"""The per-core resource model: what a block of neurons needs from the core that holds it.

A population is cut into **blocks**, contiguous runs of its neurons in memory
(row-major) order (:class:`~compiler.hardware.blocks.Blocks`).  For one block ``B``
of population ``T`` the model counts, exactly and in
:data:`~compiler.hardware.profile.BUDGETS` order:

``neurons``
    ``|B|``.
``input_axons`` (fan-in lines)
    the distinct source neurons ``(S, j)`` with at least one synapse into ``B``,
    summed over source populations (a source reached by two projections needs
    one line); see :mod:`compiler.hardware.reach`.
``output_axons`` (fan-out lines)
    the pairs (neuron of ``B``, target population) with at least one synapse
    from that neuron into that population (one line per target population; the
    fabric multicasts it to every core that holds targets).
``synapse_bits``
    stored entries × ``bits_per_synapse``.  Without weight sharing an entry is one
    synapse instance into ``B`` (stencil taps that fall off a ``clip`` edge are no
    synapse).  With ``shared_weights_per_core`` a matrix projection stores, once,
    the columns ``p`` its neurons in ``B`` use (``Σ_p nnz(W[:, p])``) and a stencil
    its ``n_taps`` kernel.

Notes
-----
A :class:`DemandModel` computes once per population (or instance) the per-neuron
quantities, so that the amounts of any blocks follow in :math:`O(N)`: fan-out
lines and unshared entries are prefix sums :math:`C` of per-neuron counts, a
block ``[lo, hi)`` gets :math:`C_{hi} - C_{lo}`.  A shared matrix column is
charged where it first occurs in a block: with :math:`p_i` the column of neuron
position ``i`` and :math:`\text{prev}_i` the last position before ``i`` with the
same column (−1 if none),

.. math:: \text{entries}(B) = \sum_{i \in B,\ \text{prev}_i < lo(B)} \text{nnz}(W_{:, p_i}).

One block of all the neurons (every population on ``unbounded``) needs only totals,
summed over chunks with a mark per matrix column, in memory independent of :math:`N`;
the prefix sums (some 50 bytes per neuron) are built when blocks are cut.  Fan-in lines
need the reached sources (:func:`~compiler.hardware.reach.reach_sweep`).  Models are
remembered per network (while it lives) and population, and remember the demands
they measured: networks and projections are treated as immutable once split.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import MatrixProjection, Population, SpikingNetwork
>>> net = SpikingNetwork(name="t", n_steps=4, populations=[
...     Population(id="x", shape={"rep": 2, "i": 3}, source=True),
...     Population(id="y", shape={"rep": 2, "o": 2})],
...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
...                                   produce=("o",), weights=np.array([[1., 0], [1, 0], [0, 1]]))])
>>> d = block_demand(net, "y", Blocks.uniform("y", 4, 2), bits_per_synapse=10,
...                  shared_weights=False)
>>> d.amounts.tolist()    # per block: neurons, fan-in, fan-out, bits
[[2, 3, 0, 30], [2, 3, 0, 30]]
"""

from __future__ import annotations

from collections.abc import Iterator
from weakref import WeakKeyDictionary

import numpy as np

from compiler.hardware.blocks import Blocks, Demand
from compiler.hardware.projection_info import ProjectionInfo, has_synapse_out, projection_info
from compiler.hardware.reach import sweep_infos
from compiler.hardware.synapses import (
    coords,
    ravel,
    stencil_degree_map,
    stored_synapses,
    synapse_instances,
)
from compiler.snn import SpikingNetwork

__all__ = ["Blocks", "Demand", "DemandModel", "ProjectionInfo", "block_demand", "demand_model",
           "has_synapse_out", "projection_info", "stencil_degree_map", "stored_synapses",
           "synapse_instances"]

_CHUNK = 1 << 21  # neurons handled at once when building a model
_MODELS: WeakKeyDictionary = WeakKeyDictionary()


def _cum(counts: np.ndarray) -> np.ndarray:
    """Prefix sums with a leading 0: block ``[lo, hi)`` totals ``c[hi] - c[lo]``."""
    out = np.zeros(counts.size + 1, np.int64)
    np.cumsum(counts, out=out[1:])
    return out


class DemandModel:
    """The per-neuron quantities of one population (or one instance of it), computed once.

    One block of all the neurons is measured by totals over chunks of neurons; the
    per-neuron prefix sums are built when blocks are first cut.

    Parameters
    ----------
    network : SpikingNetwork
        The (validated) network.
    population : str
        A neuron population.
    neurons : ndarray, optional
        Ascending flat indices the blocks will cut (``None``: the whole population).
    shared_weights : bool
        Whether shared matrices/kernels are stored once per block.
    """

    def __init__(self, network: SpikingNetwork, population: str,
                 neurons: np.ndarray | None = None, *, shared_weights: bool) -> None:
        pops = network.population
        tgt = pops[population]
        incoming = [projection_info(p, pops[p.source], tgt) for p in network.incoming(population)]
        # no reference to the network: models are remembered per network, weakly
        self._pops, self._tgt, self._incoming, self._neurons = pops, tgt, incoming, neurons
        self._n = tgt.size if neurons is None else len(neurons)
        self.shared_weights = shared_weights
        outgoing: dict[str, list[ProjectionInfo]] = {}
        for p in network.projections:
            if p.source == population:
                outgoing.setdefault(p.target, []).append(projection_info(p, tgt, pops[p.target]))
        self._outgoing = list(outgoing.values())
        self._degree = [(i.proj.axes, i.proj.degree_map(tgt, incoming=True))
                        for i in incoming if not i.shared_matrix]
        self._matrices = [i for i in incoming if i.shared_matrix]
        self._kernel_taps = sum(i.kernel_taps for i in incoming)
        self._whole: tuple[int, int, int] | None = None  # one block: fan-out, unshared, shared
        self._prefix: dict | None = None                 # per-neuron prefix sums, when cut
        self._fan_in: dict[bytes, np.ndarray] = {}
        self._demands: dict[tuple, Demand] = {}

    def _chunks(self) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]]:
        """Per chunk of positions: fan-out lines, unshared entries, each matrix's columns."""
        tgt, neurons = self._tgt, self._neurons
        for lo in range(0, self._n, _CHUNK):
            pos = np.arange(lo, min(self._n, lo + _CHUNK), dtype=np.int64)
            flat = pos if neurons is None else neurons[pos]
            fan_out, unshared = np.zeros(pos.size, np.int64), np.zeros(pos.size, np.int64)
            for infos in self._outgoing:
                has = np.zeros(flat.size, bool)
                for info in infos:
                    has |= has_synapse_out(info, tgt, flat)
                fan_out += has
            for axes, deg in self._degree:
                unshared += deg[tuple(coords(tgt, flat, axes))]
            cols = []
            for info in self._matrices:
                produce = info.proj.produce
                cols.append(ravel(tgt, flat, produce))
                unshared += info.indeg[cols[-1]]
            yield pos, fan_out, unshared, cols

    def _whole_totals(self) -> tuple[int, int, int]:
        """Fan-out lines, unshared and shared entries of one block of all the neurons."""
        if self._whole is None:
            fan_out = unshared = 0
            seen = [np.zeros(info.indeg.size, bool) for info in self._matrices]
            for _, f, u, cols in self._chunks():
                fan_out, unshared = fan_out + int(f.sum()), unshared + int(u.sum())
                for s, c in zip(seen, cols, strict=True):
                    s[c] = True
            shared = self._kernel_taps * (self._n > 0) + sum(
                int(info.indeg[s].sum()) for info, s in zip(self._matrices, seen, strict=True))
            self._whole = fan_out, unshared, shared
        return self._whole

    def _prefixes(self) -> dict:
        """Prefix sums of fan-out lines, unshared and first-charged shared entries, and the
        repeated columns ``(position, previous position with its column, nnz)`` per matrix."""
        if self._prefix is None:
            n = self._n
            fan_out, unshared = np.zeros(n, np.int64), np.zeros(n, np.int64)
            columns = [np.zeros(n, np.int64) for _ in self._matrices]
            for pos, f, u, cols in self._chunks():
                fan_out[pos], unshared[pos] = f, u
                for col, c in zip(columns, cols, strict=True):
                    col[pos] = c
            once = np.zeros(n, np.int64)  # shared: columns charged in whatever block holds them
            repeats = []
            used = zip(self._matrices, columns, strict=True) if self.shared_weights else ()
            for info, col in used:  # unshared entries need neither
                order = np.argsort(col, kind="stable")
                same = col[order[1:]] == col[order[:-1]]
                first = order[np.concatenate([[True], ~same])]
                once[first] += info.indeg[col[first]]
                pos, prev = order[1:][same], order[:-1][same]
                repeats.append((pos, prev, info.indeg[col[pos]]))
            self._prefix = {"fan_out": _cum(fan_out), "unshared": _cum(unshared),
                            "once": _cum(once), "repeats": repeats}
        return self._prefix

    def _is_whole(self, blocks: Blocks) -> bool:
        return blocks.n_blocks == 1 and blocks.edges[0] == 0 and blocks.edges[1] == self._n

    def _totals(self, name: str, blocks: Blocks) -> np.ndarray:
        cum, edges = self._prefixes()[name], blocks.edges
        return cum[edges[1:]] - cum[edges[:-1]]

    def fan_out(self, blocks: Blocks) -> np.ndarray:
        """Fan-out lines per block."""
        if self._is_whole(blocks):
            return np.array([self._whole_totals()[0]], np.int64)
        return self._totals("fan_out", blocks)

    def entries(self, blocks: Blocks) -> np.ndarray:
        """Stored synapse entries per block."""
        if self._is_whole(blocks):
            return np.array([self._whole_totals()[2 if self.shared_weights else 1]], np.int64)
        if not self.shared_weights:
            return self._totals("unshared", blocks)
        nb = blocks.n_blocks
        out = self._totals("once", blocks) + self._kernel_taps * (blocks.sizes > 0)
        if repeats := self._prefixes()["repeats"]:
            blk = blocks.block_of(np.arange(self._n))
            for pos, prev, nnz in repeats:
                b = blk[pos]
                new = (b != blk[prev]) & (b >= 0) & (b < nb)
                out += np.bincount(b[new], weights=nnz[new], minlength=nb).astype(np.int64)
        return out

    def fan_in(self, blocks: Blocks) -> np.ndarray:
        """Fan-in lines per block (remembered per block edges)."""
        key = blocks.edges.tobytes()
        if key not in self._fan_in:
            self._fan_in[key] = sweep_infos(self._pops, self._tgt, self._incoming, blocks)[0]
        return self._fan_in[key]

    def _stack(self, blocks: Blocks, lines: np.ndarray, entries: np.ndarray,
               bits_per_synapse: int) -> np.ndarray:
        return np.stack([blocks.sizes, lines, self.fan_out(blocks), entries * bits_per_synapse],
                        axis=1).astype(np.int64)

    def amounts(self, blocks: Blocks, *, bits_per_synapse: int, fan_in: bool) -> np.ndarray:
        """Per block ``neurons, input_axons, output_axons, synapse_bits`` (int64, ``(n, 4)``).

        Without ``fan_in`` the ``input_axons`` column is 0.
        """
        lines = self.fan_in(blocks) if fan_in else np.zeros(blocks.n_blocks, np.int64)
        return self._stack(blocks, lines, self.entries(blocks), bits_per_synapse)

    def demand(self, blocks: Blocks, *, bits_per_synapse: int, reach: bool) -> Demand:
        """The :class:`Demand` of ``blocks``, with fan-in and reached pairs when ``reach``.

        Remembered per block edges, ``bits_per_synapse`` and ``reach``.  The fan-in
        lines and reached pairs are counted when first read (:attr:`Demand.amounts`,
        :attr:`Demand.reach`): a split that is not kept never pays for them.
        """
        key = (blocks.edges.tobytes(), bits_per_synapse, reach)
        if key not in self._demands:
            entries = self.entries(blocks)
            lines = np.zeros(blocks.n_blocks, np.int64)
            if reach and key[0] in self._fan_in:
                lines = self._fan_in[key[0]]
            amounts = self._stack(blocks, lines, entries, bits_per_synapse)
            pending = None
            if reach:
                def pending() -> tuple[np.ndarray, dict]:
                    lines, pairs = sweep_infos(self._pops, self._tgt, self._incoming, blocks)
                    self._fan_in[key[0]] = lines
                    return lines, pairs
            self._demands[key] = Demand(blocks, amounts, entries, {}, pending=pending)
        return self._demands[key]


def demand_model(network: SpikingNetwork, population: str, neurons: np.ndarray | None = None,
                 *, shared_weights: bool) -> DemandModel:
    """The :class:`DemandModel` of ``population`` (remembered while ``network`` lives).

    A model is reused while the network holds the same population and projection
    objects; changing them builds a new one.
    """
    parts = (*network.projections, *network.populations)
    key = (population, None if neurons is None else np.asarray(neurons, np.int64).tobytes(),
           shared_weights)
    per_net = _MODELS.setdefault(network, {})
    found = per_net.get(key)
    if found is None or len(found[0]) != len(parts) or any(
            a is not b for a, b in zip(found[0], parts, strict=True)):
        found = per_net[key] = (parts, DemandModel(network, population, neurons,
                                                   shared_weights=shared_weights))
    return found[1]


def block_demand(network: SpikingNetwork, population: str, blocks: Blocks, *,
                 bits_per_synapse: int, shared_weights: bool, reach: bool = True) -> Demand:
    """Count what each block of ``population`` needs from a core (see the module docstring).

    Parameters
    ----------
    network : SpikingNetwork
        The (validated) network.
    population : str
        A neuron population (not a spike source).
    blocks : Blocks
        The blocks to measure.
    bits_per_synapse : int
        Bits of one stored entry.
    shared_weights : bool
        Whether shared matrices/kernels are stored once per block.
    reach : bool
        Whether to count fan-in lines (and keep the reached pairs for the traffic).
        Without it the ``input_axons`` column is 0 and ``reach`` is empty.

    Returns
    -------
    Demand
    """
    model = demand_model(network, population, blocks.neurons, shared_weights=shared_weights)
    return model.demand(blocks, bits_per_synapse=bits_per_synapse, reach=reach)
