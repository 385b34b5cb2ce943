r"""The per-core resource model: what a block of neurons needs from the core that holds it.

A population is cut into **blocks**, contiguous runs of its neurons in memory
(row-major) order.  For one block ``B`` of population ``T`` the model counts,
exactly and in :data:`~compiler.hardware.profile.BUDGETS` order:

``neurons``
    ``|B|``.
``input_axons`` (fan-in lines)
    the distinct source neurons ``(S, j)`` with at least one synapse into ``B``,
    summed over source populations (a source reached by two projections needs
    one line).
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

Everything is vectorized over neurons in chunks (bounded memory); the Python
loops run over blocks-groups, chunks and projections only.

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

from dataclasses import dataclass
from math import prod

import numpy as np
import scipy.sparse as sp

from compiler.snn import MatrixProjection, Population, SpikingNetwork, StencilProjection

__all__ = ["Blocks", "Demand", "ProjectionInfo", "block_demand", "has_synapse_out",
           "projection_info", "stencil_degree_map", "stored_synapses", "synapse_instances"]

_CHUNK = 1 << 21          # neuron x tap pairs handled at once
_MARK_LIMIT = 1 << 25     # booleans in one (blocks x source neurons) mark matrix


@dataclass(frozen=True, eq=False)
class Blocks:
    """Contiguous blocks of one population: block ``i`` holds neurons ``edges[i] … edges[i+1]-1``.

    With ``neurons`` (ascending flat indices, e.g. one instance of a time-multiplexed
    stage) the blocks cut that list instead: block ``i`` holds
    ``neurons[edges[i]:edges[i+1]]`` and the other neurons are in no block.

    Examples
    --------
    >>> b = Blocks.uniform("y", 10, 3)
    >>> b.edges.tolist(), b.sizes.tolist(), b.block_of(np.array([0, 4, 9])).tolist()
    ([0, 3, 6, 10], [3, 3, 4], [0, 1, 2])
    >>> i = Blocks.uniform("y", 4, 2, neurons=np.array([0, 1, 6, 7]))
    >>> i.block_of_neuron(np.array([1, 6, 3])).tolist(), i.flat(np.array([2, 3])).tolist()
    ([0, 1, -1], [6, 7])
    """

    population: str
    edges: np.ndarray
    neurons: np.ndarray | None = None

    @classmethod
    def uniform(cls, population: str, size: int, n_blocks: int, *,
                neurons: np.ndarray | None = None) -> Blocks:
        """``n_blocks`` blocks whose sizes differ by at most one: ``edges[i] = floor(i·size/n)``.

        ``size`` is ``len(neurons)`` when ``neurons`` is given.
        """
        return cls(population, (np.arange(n_blocks + 1, dtype=np.int64) * size) // n_blocks,
                   neurons)

    @property
    def n_neurons(self) -> int:
        """Neurons covered by the blocks."""
        return int(self.edges[-1])

    def flat(self, positions: np.ndarray) -> np.ndarray:
        """The flat neuron index of each position ``0 … n_neurons-1`` in block order."""
        return positions if self.neurons is None else self.neurons[positions]

    def block_of_neuron(self, flat: np.ndarray) -> np.ndarray:
        """The block of each flat neuron index; ``-1`` for a neuron in no block."""
        if self.neurons is None:
            return self.block_of(flat)
        pos = np.minimum(np.searchsorted(self.neurons, flat), len(self.neurons) - 1)
        return np.where(self.neurons[pos] == flat, self.block_of(pos), -1)

    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return len(self.edges) - 1

    @property
    def sizes(self) -> np.ndarray:
        """Neurons per block."""
        return np.diff(self.edges)

    def block_of(self, positions: np.ndarray) -> np.ndarray:
        """The block index of each position (the flat index when ``neurons`` is ``None``)."""
        return np.searchsorted(self.edges, positions, side="right") - 1


@dataclass(frozen=True, eq=False)
class Demand:
    """What each block of one population needs (see the module docstring).

    Attributes
    ----------
    blocks : Blocks
        The blocks measured.
    amounts : ndarray of int64, shape (n_blocks, 4)
        ``neurons, input_axons, output_axons, synapse_bits`` per block.
    entries : ndarray of int64
        Stored synapse entries per block.
    reach : dict of str to (ndarray, ndarray)
        Per source population: the distinct ``(block, source flat index)`` pairs.
    """

    blocks: Blocks
    amounts: np.ndarray
    entries: np.ndarray
    reach: dict[str, tuple[np.ndarray, np.ndarray]]


def _strides(pop: Population) -> dict[str, int]:
    dims = pop.dims
    return {a: prod(dims[i + 1:]) for i, a in enumerate(pop.axes)}


def _coords(pop: Population, flat: np.ndarray, axes: tuple[str, ...]) -> list[np.ndarray]:
    """Coordinates of flat neuron indices along ``axes``."""
    strides = _strides(pop)
    return [(flat // strides[a]) % pop.shape[a] for a in axes]


def _ravel(coords: list[np.ndarray], sizes: list[int]) -> np.ndarray:
    out = np.zeros_like(coords[0]) if coords else np.zeros(0, np.int64)
    for c, n in zip(coords, sizes, strict=True):
        out = out * n + c
    return out


def _pattern(proj: MatrixProjection) -> sp.csr_matrix:
    """Boolean ``(n_in, n_out)`` pattern of the non-zero weights."""
    if proj.weights is not None:
        return sp.csr_matrix(proj.weights != 0)
    keep = proj.values != 0
    m = sp.csr_matrix((np.ones(int(keep.sum()), bool), (proj.rows[keep], proj.cols[keep])),
                      shape=proj.n_in_out)
    m.sum_duplicates()
    return m.astype(bool)


def stencil_degree_map(proj: StencilProjection, pop: Population, *, incoming: bool) -> np.ndarray:
    r"""Synapses per neuron over the stencil's map axes (in ``proj.axes`` order).

    ``incoming``: :math:`\sum_o [K_o \ne 0]\,[x + o \in \text{map}]` (taps a target
    neuron receives); otherwise :math:`\sum_o [K_o \ne 0]\,[x - o \in \text{map}]`
    (targets a source neuron reaches).  ``wrap`` axes never lose a tap.

    Examples
    --------
    >>> from compiler.snn import Population, StencilProjection
    >>> k = StencilProjection(id="s", source="a", target="b", axes=("r",),
    ...                       kernel=np.array([1.0, 1.0, 1.0]), edge=("clip",))
    >>> stencil_degree_map(k, Population(id="b", shape={"r": 4}), incoming=True).tolist()
    [2, 3, 3, 2]
    """
    mask = (proj.kernel != 0).astype(np.float64)
    inside = np.ones([pop.shape[a] for a in proj.axes])
    pad = [(r, r) for r in proj.radius]
    for ax, (edge, width) in enumerate(zip(proj.edge, pad, strict=True)):
        widths = [(0, 0)] * inside.ndim
        widths[ax] = width
        inside = np.pad(inside, widths, mode="wrap" if edge == "wrap" else "constant")
    from scipy import signal  # imported here: scipy.signal takes ~1 s to import

    op = signal.correlate if incoming else signal.convolve
    return np.rint(op(inside, mask, mode="valid")).astype(np.int64)


def synapse_instances(proj: MatrixProjection | StencilProjection,
                      pops: dict[str, Population]) -> int:
    """Synapses of ``proj`` counting every repetition; stencil taps off a ``clip`` edge excluded.

    Examples
    --------
    >>> from compiler.snn import Population, StencilProjection
    >>> pops = {"b": Population(id="b", shape={"r": 4})}
    >>> synapse_instances(StencilProjection(id="k", source="b", target="b", axes=("r",),
    ...                                     kernel=np.ones(3), edge=("clip",)), pops)
    10
    """
    if isinstance(proj, StencilProjection):
        tgt = pops[proj.target]
        deg = stencil_degree_map(proj, tgt, incoming=True)
        return int(deg.sum()) * (tgt.size // deg.size)
    src = pops[proj.source]
    reps = src.size // prod(src.shape[a] for a in proj.contract)
    return reps * int(_pattern(proj).nnz)


def stored_synapses(network: SpikingNetwork, shared_weights: bool) -> int:
    """A lower bound on the entries a network stores: shared weights once, else every instance.

    Examples
    --------
    >>> from compiler.snn import Population, SpikingNetwork, StencilProjection
    >>> net = SpikingNetwork(name="s", n_steps=2, populations=[
    ...     Population(id="a", shape={"r": 4}, source=True), Population(id="b", shape={"r": 4})],
    ...     projections=[StencilProjection(id="k", source="a", target="b", axes=("r",),
    ...                                    kernel=np.ones(3), edge=("clip",))])
    >>> stored_synapses(net, True), stored_synapses(net, False)
    (3, 10)
    """
    pops = network.population
    if shared_weights:
        return sum(p.n_synapses for p in network.projections)
    return sum(synapse_instances(p, pops) for p in network.projections)


# --------------------------------------------------------------------------- per projection
@dataclass(frozen=True, eq=False)
class ProjectionInfo:
    """What the per-chunk counting needs of one projection, computed once."""

    proj: MatrixProjection | StencilProjection
    pattern: sp.csr_matrix | None = None     # matrix: (n_in, n_out) non-zero pattern
    pattern_t: sp.csr_matrix | None = None   # matrix: its transpose, CSR
    indeg: np.ndarray | None = None          # matrix: synapses per column
    rownz: np.ndarray | None = None          # matrix: rows with a synapse
    offsets: np.ndarray | None = None        # matrix: flat source offset per row; stencil: taps
    out_map: np.ndarray | None = None        # stencil: has-target map over the stencil axes


def projection_info(proj, src: Population, tgt: Population) -> ProjectionInfo:
    """Precompute what the per-chunk counting needs of ``proj`` (from ``src`` to ``tgt``)."""
    if isinstance(proj, StencilProjection):
        taps = np.argwhere(proj.kernel != 0) - np.array(proj.radius)
        return ProjectionInfo(proj, offsets=taps,
                     out_map=stencil_degree_map(proj, src, incoming=False) > 0)
    pattern = _pattern(proj)
    s_str = _strides(src)
    idx = np.unravel_index(np.arange(proj.n_in), [src.shape[a] for a in proj.contract])
    off = np.zeros(proj.n_in, np.int64)
    for a, c in zip(proj.contract, idx, strict=True):
        off += c * s_str[a]
    return ProjectionInfo(proj, pattern=pattern, pattern_t=pattern.T.tocsr(),
                 indeg=np.asarray(pattern.sum(axis=0)).ravel().astype(np.int64),
                 rownz=np.asarray(pattern.sum(axis=1)).ravel() > 0, offsets=off)


def _matrix_in(info, src, tgt, flat, blk, mark, entries, shared, row0, used):
    """Mark reached sources; add stored entries of target neurons ``flat`` in blocks ``blk``."""
    proj = info.proj
    rep_axes = tuple(a for a in tgt.axes if a not in proj.produce)
    p = _ravel(_coords(tgt, flat, proj.produce), [tgt.shape[a] for a in proj.produce])
    s_str = _strides(src)
    base = np.zeros_like(flat)
    for a, c in zip(rep_axes, _coords(tgt, flat, rep_axes), strict=True):
        base += c * s_str[a]
    if shared:
        used.append(np.unique(blk * proj.n_out + p))
    else:
        entries += np.bincount(blk, weights=info.indeg[p], minlength=len(entries)).astype(
            np.int64)
    if mark is None:
        return
    pair_key, pair_id = np.unique(blk * src.size + base, return_inverse=True)
    ind = sp.csr_matrix((np.ones(flat.size, bool), (pair_id, p)),
                        shape=(pair_key.size, proj.n_out))
    hit = (ind @ info.pattern_t).tocoo()
    key = pair_key[hit.row]
    mark(key // src.size - row0, key % src.size + info.offsets[hit.col])


def _stencil_in(info, src, tgt, flat, blk, mark, entries, shared, row0, used):
    proj, offsets = info.proj, info.offsets
    n_taps = len(offsets)
    coords = _coords(tgt, flat, proj.axes)
    strides = _strides(tgt)
    src_idx = np.repeat(flat[:, None], n_taps, axis=1)
    valid = np.ones((flat.size, n_taps), bool)
    for i, a in enumerate(proj.axes):
        c = coords[i][:, None] + offsets[None, :, i]
        n = tgt.shape[a]
        if proj.edge[i] == "wrap":
            c = c % n
        else:
            valid &= (c >= 0) & (c < n)
        src_idx += (c - coords[i][:, None]) * strides[a]
    if shared:
        used.append(np.unique(blk))
    else:
        entries += np.bincount(blk, weights=valid.sum(axis=1), minlength=len(entries)).astype(
            np.int64)
    if mark is not None:
        mark(np.broadcast_to(blk[:, None], valid.shape)[valid] - row0, src_idx[valid])


def has_synapse_out(info: ProjectionInfo, pop: Population, flat: np.ndarray) -> np.ndarray:
    """Whether each neuron of ``pop`` (flat indices) has a synapse in the projection."""
    proj = info.proj
    if isinstance(proj, StencilProjection):
        return info.out_map[tuple(_coords(pop, flat, proj.axes))]
    c = _ravel(_coords(pop, flat, proj.contract), [pop.shape[a] for a in proj.contract])
    return info.rownz[c]


def _single_block(network, tgt, blocks, by_source, outgoing, bits, shared) -> Demand:
    pops = network.population
    infos = [i for v in by_source.values() for i in v]
    if shared:
        entries = sum(len(i.offsets) if i.proj.kind == "stencil" else int(i.indeg.sum())
                      for i in infos)
    else:
        entries = sum(synapse_instances(i.proj, pops) for i in infos)
    fan_out = 0
    for lo in range(0, tgt.size, _CHUNK):
        flat = np.arange(lo, min(tgt.size, lo + _CHUNK), dtype=np.int64)
        for projs in outgoing.values():
            has = np.zeros(flat.size, bool)
            for info in projs:
                has |= has_synapse_out(info, tgt, flat)
            fan_out += int(has.sum())
    amounts = np.array([[tgt.size, 0, fan_out, entries * bits]], np.int64)
    return Demand(blocks=blocks, amounts=amounts, entries=np.array([entries], np.int64),
                  reach={})


def _add_shared(info: ProjectionInfo, used: list[np.ndarray], entries: np.ndarray) -> None:
    """Charge shared weights once per block: the columns (matrix) or the kernel (stencil) used."""
    if not used:
        return
    keys = np.unique(np.concatenate(used))
    if info.proj.kind == "stencil":
        entries[keys] += len(info.offsets)
    else:
        n_out = info.proj.n_out
        np.add.at(entries, keys // n_out, info.indeg[keys % n_out])


_INCOMING = {"matrix": _matrix_in, "stencil": _stencil_in}


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
    pops = network.population
    tgt = pops[population]
    edges = blocks.edges
    nb = blocks.n_blocks
    entries = np.zeros(nb, np.int64)
    fan_out = np.zeros(nb, np.int64)
    incoming = network.incoming(population)
    by_source: dict[str, list] = {}
    for proj in incoming:
        by_source.setdefault(proj.source, []).append(projection_info(proj, pops[proj.source], tgt))
    outgoing: dict[str, list] = {}
    for proj in network.projections:
        if proj.source == population:
            info = projection_info(proj, tgt, pops[proj.target])
            outgoing.setdefault(proj.target, []).append(info)
    if nb == 1 and not reach and blocks.neurons is None:
        # one block of the whole population: closed-form entries, only fan-out needs a sweep
        return _single_block(network, tgt, blocks, by_source, outgoing, bits_per_synapse,
                             shared_weights)
    pairs: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {s: [] for s in by_source}
    fan_in = np.zeros(nb, np.int64)
    used: dict[str, list[np.ndarray]] = {p.id: [] for p in incoming}  # shared: (block, column)
    biggest = max((pops[s].size for s in by_source), default=1)
    per_group = max(1, _MARK_LIMIT // biggest)
    for g0 in range(0, nb, per_group):
        g1 = min(nb, g0 + per_group)
        marks = {s: np.zeros((g1 - g0, pops[s].size), bool) for s in by_source} if reach else {}
        taps = max([len(i.offsets) for v in by_source.values() for i in v
                    if i.proj.kind == "stencil"] + [1])
        step = max(1, _CHUNK // taps)
        for lo in range(int(edges[g0]), int(edges[g1]), step):
            pos = np.arange(lo, min(lo + step, int(edges[g1])), dtype=np.int64)
            flat, blk = blocks.flat(pos), blocks.block_of(pos)
            for s, projs in by_source.items():
                mark = None
                if reach:
                    m = marks[s]

                    def mark(rows, cols, m=m):
                        m[rows, cols] = True
                for info in projs:
                    _INCOMING[info.proj.kind](info, pops[s], tgt, flat, blk, mark, entries,
                                              shared_weights, g0, used[info.proj.id])
            for projs in outgoing.values():
                has = np.zeros(flat.size, bool)
                for info in projs:
                    has |= has_synapse_out(info, tgt, flat)
                fan_out += np.bincount(blk[has], minlength=nb)
        for s, m in marks.items():
            fan_in[g0:g1] += m.sum(axis=1)
            r, c = np.nonzero(m)
            pairs[s].append((r + g0, c))
    for v in by_source.values():
        for info in v:
            _add_shared(info, used[info.proj.id], entries)
    amounts = np.stack([blocks.sizes, fan_in, fan_out, entries * bits_per_synapse], axis=1)
    reached = {s: (np.concatenate([p[0] for p in v]), np.concatenate([p[1] for p in v]))
               for s, v in pairs.items() if v}
    return Demand(blocks=blocks, amounts=amounts.astype(np.int64), entries=entries,
                  reach=reached)
