"""The spiking network the compiler emits: populations, projections, encoders, decoders.

A :class:`SpikingNetwork` is plain data.  It says nothing about how it is
simulated (see ``backends.reference``) or stored (``backends.artifact``); it
only guarantees, through :meth:`SpikingNetwork.validate`, that every reference
resolves, that axes and sizes agree, and that no zero-delay cycle exists.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import (Decoder, Encoder, LatencyCode, MatrixProjection,
...                           NeuronParams, Population, SpikingNetwork)
>>> net = SpikingNetwork(
...     name="tiny", n_steps=8,
...     populations=[Population(id="in", shape={"i": 2}, source=True),
...                  Population(id="out", shape={"o": 1}, params=NeuronParams(v_th=2.0))],
...     projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
...                                   produce=("o",), weights=np.ones((2, 1)))],
...     encoders=[Encoder(port="x", population="in",
...                       code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
...     decoders=[Decoder(port="y", population="out", kind="spiked")])
>>> net.validate().n_neurons, net.n_synapses
(1, 2)
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from math import prod

import networkx as nx
from pydantic import ConfigDict, Field, field_validator

from compiler.snn.coding import N_PARTS, Decoder, Encoder
from compiler.snn.neurons import NeuronParams
from compiler.snn.projections import Projection
from compiler.snn.resonator import N_COMPARTMENTS, ResonatorParams
from ir.errors import NetworkError, NetworkValidationError
from ir.model import CheckedModel

__all__ = ["Population", "SpikingNetwork", "PART_AXIS"]

#: Name of the trailing axis that holds the parts of split values (±Re, ±Im …).
PART_AXIS = "part"


class Population(CheckedModel):
    """A tensor of neurons with named axes (or of spike sources fed by an encoder).

    Parameters
    ----------
    id : str
        Unique population id.
    shape : dict of str to int
        Named axes and their sizes, in memory order.
    params : NeuronParams or ResonatorParams
        Dynamics of every neuron (ignored for sources); resonators
        (:mod:`compiler.snn.resonator`) keep their four compartments on ``part``.
    source : bool
        True for a spike source driven by an :class:`Encoder` (no dynamics).
    origin : dict
        Provenance: ``{"node": <radar-IR node id>, "motif": <motif>}``.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = NetworkValidationError

    id: str = Field(min_length=1)
    shape: dict[str, int]
    params: ResonatorParams | NeuronParams = NeuronParams()
    source: bool = False
    origin: dict[str, str] = Field(default_factory=dict)

    @field_validator("shape")
    @classmethod
    def _sizes(cls, shape: dict[str, int]) -> dict[str, int]:
        if not shape:
            raise ValueError("a population needs at least one axis")
        bad = {a: n for a, n in shape.items() if n <= 0}
        if bad:
            raise ValueError(f"axis sizes must be positive, got {bad}")
        return shape

    def __eq__(self, other: object) -> bool:
        # dict equality ignores order, but the axis order is the memory layout
        return (isinstance(other, Population) and self.axes == other.axes
                and super().__eq__(other))

    __hash__ = None  # type: ignore[assignment]  # mutable-looking dict field: not hashable

    @property
    def axes(self) -> tuple[str, ...]:
        """Axis names in memory order."""
        return tuple(self.shape)

    @property
    def dims(self) -> tuple[int, ...]:
        """Axis sizes in memory order."""
        return tuple(self.shape.values())

    @property
    def size(self) -> int:
        """Number of neurons (or sources)."""
        return prod(self.dims)


@dataclass(eq=False)
class SpikingNetwork:
    """A compiled spiking network: the simulator's and the exporters' input.

    Parameters
    ----------
    name : str
        Name (usually the chain's).
    n_steps : int
        Time steps of one frame.
    populations, projections, encoders, decoders : iterables
        The parts; ids must be unique within populations and within projections.
    meta : dict
        Free-form JSON-able metadata (calibration policy, target, …).
    """

    name: str
    n_steps: int
    populations: list[Population] = field(default_factory=list)
    projections: list[Projection] = field(default_factory=list)
    encoders: list[Encoder] = field(default_factory=list)
    decoders: list[Decoder] = field(default_factory=list)
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.populations = list(self.populations)
        self.projections = list(self.projections)
        self.encoders = list(self.encoders)
        self.decoders = list(self.decoders)

    # ------------------------------------------------------------------ lookup
    @property
    def population(self) -> Mapping[str, Population]:
        """Populations by id."""
        return {p.id: p for p in self.populations}

    @property
    def projection(self) -> Mapping[str, Projection]:
        """Projections by id."""
        return {p.id: p for p in self.projections}

    def incoming(self, population_id: str) -> list[Projection]:
        """Projections that target ``population_id``, in declaration order."""
        return [p for p in self.projections if p.target == population_id]

    # ------------------------------------------------------------------ counts
    @property
    def n_neurons(self) -> int:
        """Neurons (sources excluded), counting every repetition."""
        return sum(p.size for p in self.populations if not p.source)

    @property
    def n_inputs(self) -> int:
        """Spike sources, counting every repetition."""
        return sum(p.size for p in self.populations if p.source)

    @property
    def n_synapses(self) -> int:
        """Stored synapses: shared weights count once (one copy per motif)."""
        return sum(p.n_synapses for p in self.projections)

    def n_synapse_instances(self) -> int:
        """Synapses counting every repetition and stencil position (what a chip would wire)."""
        pops = self.population
        return sum(p.n_synapse_instances(pops[p.source], pops[p.target])
                   for p in self.projections)

    # ------------------------------------------------------------------ checks
    def validate(self) -> SpikingNetwork:
        """Check every reference, axis and size; return ``self`` or raise :class:`NetworkError`.

        Raises
        ------
        NetworkError
            Naming the population, projection or port at fault.
        """
        if self.n_steps <= 0:
            raise NetworkError(f"network {self.name!r}: n_steps must be positive, got "
                               f"{self.n_steps}")
        pops = _unique(self.populations, "population")
        _unique(self.projections, "projection")
        for proj in self.projections:
            for end in (proj.source, proj.target):
                if end not in pops:
                    raise NetworkError(
                        f"projection {proj.id!r}: unknown population {end!r}; known: "
                        f"{sorted(pops)}", node=proj.id)
            if pops[proj.target].source:
                raise NetworkError(f"projection {proj.id!r}: target {proj.target!r} is a spike "
                                   "source and cannot receive input", node=proj.id)
            proj.check_axes(pops[proj.source], pops[proj.target])
        _check_ports(self.encoders, pops, "encoder", want_source=True)
        _check_ports(self.decoders, pops, "decoder", want_source=None)
        for port in (*self.encoders, *self.decoders):
            _check_split(port, pops[port.population])
        fed_twice = [e.population for e in self.encoders]
        for pid in {p for p in fed_twice if fed_twice.count(p) > 1}:
            raise NetworkError(f"population {pid!r}: fed by more than one encoder", node=pid)
        for dec in self.decoders:
            if dec.kind == "membrane" and pops[dec.population].source:
                raise NetworkError(f"decoder {dec.port!r}: a spike source {dec.population!r} has "
                                   "no membrane; use kind 'spike_time', 'count' or 'spiked'",
                                   node=dec.port)
        for p in self.populations:
            par = p.params
            if par.scale_axis is not None and (par.scale_axis not in p.shape or
                                               p.shape[par.scale_axis] != len(par.scales)):
                raise NetworkError(
                    f"population {p.id!r}: {len(par.scales)} per-neuron scales along "
                    f"{par.scale_axis!r}, but its shape is {dict(p.shape)}; give one scale per "
                    "index of an axis of the population", node=p.id)
            if isinstance(par, ResonatorParams) and (
                    p.axes[-1:] != (PART_AXIS,) or p.shape[PART_AXIS] != N_COMPARTMENTS
                    or p.shape.get(par.axis) != par.n_bins):
                raise NetworkError(
                    f"population {p.id!r}: a resonator population needs a trailing "
                    f"{PART_AXIS!r} axis of {N_COMPARTMENTS} and axis {par.axis!r} of "
                    f"{par.n_bins} (its coefficients); its shape is {dict(p.shape)}", node=p.id)
        fed = {e.population for e in self.encoders}
        for p in self.populations:
            if p.source and p.id not in fed:
                raise NetworkError(f"population {p.id!r}: a spike source with no encoder; add an "
                                   "Encoder for it", node=p.id)
        self.population_order()
        return self

    def population_order(self) -> list[str]:
        """Population ids ordered so zero-delay projections run source before target.

        Raises
        ------
        NetworkError
            If zero-delay projections form a cycle (a same-step loop).
        """
        g = nx.DiGraph()
        g.add_nodes_from(p.id for p in self.populations)
        for proj in self.projections:
            if proj.min_delay() == 0:
                g.add_edge(proj.source, proj.target)
        try:
            return list(nx.lexicographical_topological_sort(g))
        except nx.NetworkXUnfeasible:
            cycle = [u for u, _ in nx.find_cycle(g)]
            raise NetworkError(
                f"network {self.name!r}: zero-delay projections form a cycle through {cycle}; "
                "give at least one projection on the loop a delay >= 1",
                node=cycle[0]) from None

    def is_feedforward(self) -> bool:
        """Whether the population graph (all projections) has no cycle."""
        g = nx.DiGraph([(p.source, p.target) for p in self.projections])
        return nx.is_directed_acyclic_graph(g)


def _unique(items: Iterable, what: str) -> dict:
    out: dict = {}
    for item in items:
        if item.id in out:
            raise NetworkError(f"duplicate {what} id {item.id!r}", node=item.id)
        out[item.id] = item
    return out


def _check_ports(items: list, pops: dict, what: str, want_source: bool | None) -> None:
    ports: set[str] = set()
    for item in items:
        if item.port in ports:
            raise NetworkError(f"duplicate {what} port {item.port!r}", node=item.port)
        ports.add(item.port)
        if item.population not in pops:
            raise NetworkError(f"{what} {item.port!r}: unknown population {item.population!r}",
                               node=item.port)
        if want_source is not None and pops[item.population].source != want_source:
            raise NetworkError(f"{what} {item.port!r}: population {item.population!r} must be a "
                               "spike source (Population(source=True))", node=item.port)


def _check_split(port: Encoder | Decoder, pop: Population) -> None:
    how = port.split if isinstance(port, Encoder) else port.combine
    parts = N_PARTS[how]
    if parts and (pop.axes[-1] != PART_AXIS or pop.dims[-1] != parts):
        what = "encoder" if isinstance(port, Encoder) else "decoder"
        raise NetworkError(f"{what} {port.port!r}: {how!r} needs population {pop.id!r} to end "
                           f"with axis {PART_AXIS!r} of size {parts}, got {pop.shape}",
                           node=port.port)
