"""Collects populations, projections, encoders and decoders into one spiking network.

Lowering rules add parts through a :class:`NetworkBuilder`; it prefixes ids
with the IR node id (``"<node>/<name>"``) so every part traces back to its
node, stamps the ``origin`` metadata, refuses duplicates, and tracks the last
time step any part uses.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import NeuronParams
>>> b = NetworkBuilder(name="demo")
>>> b.population("rng", "out", {"range": 4}, NeuronParams(v_th=1.0), motif="time").id
'rng/out'
>>> b.use_steps(12)
>>> b.finish().n_steps
12
"""

from __future__ import annotations

import numpy as np

from compiler.snn import (
    Decoder,
    Encoder,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import CompileError

__all__ = ["NetworkBuilder"]


class NetworkBuilder:
    """Accumulates one spiking network during lowering.

    Parameters
    ----------
    name : str
        The network's name.
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self._pops: dict[str, Population] = {}
        self._projs: dict[str, MatrixProjection | StencilProjection] = {}
        self._encoders: dict[str, Encoder] = {}
        self._decoders: dict[str, Decoder] = {}
        self._n_steps = 1
        self.meta: dict = {}

    # ---------------------------------------------------------------- parts
    def population(self, node: str, name: str, shape: dict[str, int],
                   params: NeuronParams | None = None, *, motif: str,
                   source: bool = False) -> Population:
        """Add a population ``"<node>/<name>"`` and return it."""
        pid = f"{node}/{name}"
        if pid in self._pops:
            raise CompileError(f"node {node!r}: population {pid!r} added twice", node=node)
        pop = Population(id=pid, shape=dict(shape), params=params or NeuronParams(),
                         source=source, origin={"node": node, "motif": motif})
        self._pops[pid] = pop
        return pop

    def matrix(self, node: str, name: str, source: str, target: str, *,
               contract: tuple[str, ...], produce: tuple[str, ...], motif: str,
               weights: np.ndarray | None = None, **sparse) -> MatrixProjection:
        """Add a :class:`MatrixProjection` ``"<node>/<name>"`` (dense ``weights`` or COO)."""
        proj = MatrixProjection(id=f"{node}/{name}", source=source, target=target,
                                contract=contract, produce=produce, weights=weights,
                                origin={"node": node, "motif": motif}, **sparse)
        return self._add_projection(node, proj)

    def stencil(self, node: str, name: str, source: str, target: str, *,
                axes: tuple[str, ...], kernel: np.ndarray, edge: tuple[str, ...], motif: str,
                delays: np.ndarray | None = None) -> StencilProjection:
        """Add a :class:`StencilProjection` ``"<node>/<name>"``."""
        proj = StencilProjection(id=f"{node}/{name}", source=source, target=target, axes=axes,
                                 kernel=kernel, edge=edge, delays=delays,
                                 origin={"node": node, "motif": motif})
        return self._add_projection(node, proj)

    def _add_projection(self, node: str, proj):
        if proj.id in self._projs:
            raise CompileError(f"node {node!r}: projection {proj.id!r} added twice", node=node)
        self._projs[proj.id] = proj
        return proj

    def encoder(self, encoder: Encoder) -> Encoder:
        """Add an encoder (its port is the IR node id whose value it reads)."""
        if encoder.port in self._encoders:
            return self._encoders[encoder.port]
        self._encoders[encoder.port] = encoder
        return encoder

    def has_encoder(self, port: str) -> bool:
        """Whether an encoder for ``port`` exists already."""
        return port in self._encoders

    def decoder(self, decoder: Decoder) -> Decoder:
        """Add a decoder (its port is the IR node id whose value it produces)."""
        if decoder.port in self._decoders and self._decoders[decoder.port] != decoder:
            raise CompileError(f"two different decoders for node {decoder.port!r}",
                               node=decoder.port)
        self._decoders[decoder.port] = decoder
        return decoder

    def use_steps(self, n_steps: int) -> None:
        """Record that some part of the network runs until step ``n_steps`` (exclusive)."""
        self._n_steps = max(self._n_steps, int(n_steps))

    # ---------------------------------------------------------------- state
    @property
    def is_empty(self) -> bool:
        """Whether nothing has been added yet."""
        return not self._pops

    def populations_of(self, node: str) -> list[Population]:
        """The populations lowered for IR node ``node`` so far."""
        return [p for p in self._pops.values() if p.origin.get("node") == node]

    @property
    def input_ports(self) -> list[str]:
        """Encoder ports so far."""
        return list(self._encoders)

    @property
    def output_ports(self) -> list[str]:
        """Decoder ports so far."""
        return list(self._decoders)

    def finish(self) -> SpikingNetwork:
        """The validated network (raises :class:`ir.errors.NetworkError` if inconsistent)."""
        net = SpikingNetwork(name=self.name, n_steps=self._n_steps,
                             populations=list(self._pops.values()),
                             projections=list(self._projs.values()),
                             encoders=list(self._encoders.values()),
                             decoders=list(self._decoders.values()),
                             meta=dict(self.meta))
        return net.validate()
