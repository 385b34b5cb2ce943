r"""Stages and their repetitions: what can be time-multiplexed, and the neurons of one instance.

A **stage** is the set of neuron populations whose ``origin["node"]`` is one IR
node (a population without an origin is a stage of its own id).  Its
**repetitions** :math:`R` is the gcd of the repetition counts of the projections
into it: a matrix shared over pass-through axes is applied
:math:`\text{source.size} / n_{in}` times, a stencil counts 1 (the rule of the
Vogginger et al.'s Table 3, used by the report).

The **repetition axes** of a stage are the pass-through axes (neither contracted
nor produced) that every projection into it shares; every projection into a
stage must be a matrix for it to have any.  A stage is **multiplexable** when
:math:`R > 1` and the product of its repetition-axis sizes is :math:`R`: then
one **instance** — the neurons with index 0 on every repetition axis — computes
one repetition, reads only instance-0 neurons of its own stage, and the R
instances are identical up to a shift of the inputs (same weights, same
counts), so one instance can be placed and run :math:`R` times per frame.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import MatrixProjection, Population, SpikingNetwork
>>> net = SpikingNetwork(name="t", n_steps=4, populations=[
...     Population(id="x", shape={"rep": 2, "i": 3}, source=True),
...     Population(id="y", shape={"rep": 2, "o": 2}, origin={"node": "fc", "motif": "dense"})],
...     projections=[MatrixProjection(id="w", source="x", target="y", contract=("i",),
...                                   produce=("o",), weights=np.ones((3, 2)))])
>>> (s,) = stages(net)
>>> s.key, s.populations, s.repetitions, s.axes, s.multiplexable
('fc', ('y',), 2, ('rep',), True)
>>> instance_neurons(net.population["y"], s.axes).tolist()
[0, 1]
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gcd, prod

import numpy as np

from compiler.hardware.synapses import synapse_instances
from compiler.snn import Population, SpikingNetwork

__all__ = ["Stage", "instance_neurons", "projection_repetitions", "stage_key", "stages"]


def stage_key(pop: Population) -> str:
    """The stage of a population: its IR node, else its own id."""
    return pop.origin.get("node", pop.id)


def projection_repetitions(proj, pops) -> int:
    """How many times a matrix is applied (``source.size / n_in``); 1 for a stencil.

    Examples
    --------
    >>> from compiler.snn import Population, StencilProjection
    >>> k = StencilProjection(id="k", source="a", target="a", axes=("r",), kernel=np.ones(3),
    ...                       edge=("clip",))
    >>> projection_repetitions(k, {"a": Population(id="a", shape={"r": 4})})
    1
    """
    return proj.repetitions(pops[proj.source])


@dataclass(frozen=True)
class Stage:
    """One stage of a network (see the module docstring).

    Attributes
    ----------
    key : str
        The IR node (or population id).
    motif : str or None
        The motif(s) of its populations, ``+``-joined.
    populations : tuple of str
        Its neuron (non-source) populations, in network order.
    repetitions : int
        :math:`R` by the gcd rule.
    axes : tuple of str
        Repetition axes shared by every projection into the stage (empty without any).
    neurons : int
        Neurons over all repetitions.
    synapse_instances : int
        Synapse instances into the stage over all repetitions (unshared storage).
    synapses_stored : int
        Synapses of its projections stored once (shared storage).
    """

    key: str
    motif: str | None
    populations: tuple[str, ...]
    repetitions: int
    axes: tuple[str, ...]
    neurons: int
    synapse_instances: int
    synapses_stored: int

    @property
    def multiplexable(self) -> bool:
        """Whether one instance can be placed and run ``repetitions`` times."""
        return self.repetitions > 1 and bool(self.axes)


def _pass_through(proj, pops) -> set[str] | None:
    return proj.repetition_axes(pops[proj.target])


def stages(network: SpikingNetwork) -> list[Stage]:
    """The stages of ``network`` in population order, with repetitions and repetition axes.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.

    Returns
    -------
    list of Stage
        Stages with at least one neuron (non-source) population.
    """
    pops = network.population
    members: dict[str, list[Population]] = {}
    for p in network.populations:
        if not p.source:
            members.setdefault(stage_key(p), []).append(p)
    out = []
    for key, neurons in members.items():
        ids = {p.id for p in neurons}
        projs = [q for q in network.projections if q.target in ids]
        r = 0
        for q in projs:
            r = gcd(r, projection_repetitions(q, pops))
        r = r or 1
        through = [_pass_through(q, pops) for q in projs]
        axes: tuple[str, ...] = ()
        if projs and all(t is not None for t in through):
            common = set.intersection(*through)
            ordered = tuple(a for a in neurons[0].axes if a in common)
            sizes = {a: neurons[0].shape[a] for a in ordered}
            same = all(all(p.shape.get(a) == n for a, n in sizes.items()) for p in neurons)
            if same and prod(sizes.values()) == r:
                axes = ordered
        motifs = sorted({p.origin.get("motif", "") for p in neurons} - {""})
        out.append(Stage(key=key, motif="+".join(motifs) or None,
                         populations=tuple(p.id for p in neurons), repetitions=r,
                         axes=axes if r > 1 else (), neurons=sum(p.size for p in neurons),
                         synapse_instances=sum(synapse_instances(q, pops) for q in projs),
                         synapses_stored=sum(q.n_synapses for q in projs)))
    return out


def instance_neurons(pop: Population, axes: tuple[str, ...]) -> np.ndarray:
    """Flat (row-major) indices of the neurons of ``pop`` with index 0 on every axis in ``axes``.

    Ascending; ``pop.size / Π sizes(axes)`` of them.

    Examples
    --------
    >>> p = Population(id="y", shape={"a": 2, "r": 3, "b": 2})
    >>> instance_neurons(p, ("r",)).tolist()
    [0, 1, 6, 7]
    """
    dims = pop.dims
    strides = [prod(dims[i + 1:]) for i in range(len(dims))]
    kept = [(n, s) for a, n, s in zip(pop.axes, dims, strides, strict=True) if a not in axes]
    flat = np.zeros(1, np.int64)
    for n, s in kept:
        flat = (flat[:, None] + np.arange(n, dtype=np.int64)[None, :] * s).ravel()
    return flat
