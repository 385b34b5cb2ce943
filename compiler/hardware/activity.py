r"""Spikes per neuron per frame: an analytic bound from the network, or a measured mean.

The bound :math:`\hat s` per population: a latency-coded source or a
``fire_once`` neuron spikes at most once per frame; a rate-coded source at most
:math:`\lceil r_{max} T \rceil` times; any other neuron at most once per step,
:math:`T` = ``n_steps``.  Measured: ``spike_counts[p] / (n_frames · size)`` of a
:class:`~backends.reference.SimResult`.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import (Encoder, LatencyCode, NeuronParams, Population,
...                           SpikingNetwork)
>>> net = SpikingNetwork(name="a", n_steps=10, populations=[
...     Population(id="x", shape={"i": 2}, source=True),
...     Population(id="y", shape={"o": 2}, params=NeuronParams(reset="fire_once")),
...     Population(id="z", shape={"o": 2})],
...     encoders=[Encoder(port="x", population="x",
...                       code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))])
>>> spike_bound(net)
{'x': 1.0, 'y': 1.0, 'z': 10.0}
"""

from __future__ import annotations

from math import ceil

from compiler.snn import LatencyCode, SpikingNetwork

__all__ = ["spike_bound", "measured_spikes"]


def spike_bound(network: SpikingNetwork) -> dict[str, float]:
    """The most spikes one neuron of each population can emit in a frame (see the module)."""
    codes = {e.population: e.code for e in network.encoders}
    out: dict[str, float] = {}
    for pop in network.populations:
        if pop.source:
            code = codes.get(pop.id)
            if code is not None and code.type == "stream":
                out[pop.id] = float(code.length)  # one spike per sample at most
                continue
            out[pop.id] = 1.0 if code is None or isinstance(code, LatencyCode) else float(
                ceil(code.max_rate * network.n_steps))
        else:
            out[pop.id] = 1.0 if pop.params.reset == "fire_once" else float(network.n_steps)
    return out


def measured_spikes(network: SpikingNetwork, sim) -> dict[str, float]:
    """Mean spikes per neuron per frame of each population in a simulation result ``sim``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from compiler.snn import Population, SpikingNetwork
    >>> net = SpikingNetwork(name="m", n_steps=4, populations=[Population(id="y", shape={"o": 4})])
    >>> measured_spikes(net, SimpleNamespace(spike_counts={"y": 6}, n_frames=3))
    {'y': 0.5}
    """
    return {p.id: sim.spike_counts.get(p.id, 0) / (sim.n_frames * p.size)
            for p in network.populations}
