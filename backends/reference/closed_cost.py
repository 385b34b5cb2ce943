r"""Wall-clock model of the closed-form engine (:mod:`backends.reference.closed`).

The closed form solves every population once for the whole batch, with array
operations whose work is proportional to the number of frames ``F``, so its time
is ``F`` times a per-frame cost read from the network's sizes alone:

.. math::

    t_{frame} = c_n \sum_p S_p
      + \sum_{q\ \mathrm{stencil}} \frac{N_q K_q \sigma_q}{R_{st}}
      + \sum_{q\ \mathrm{matrix}} \Big(\frac{R_q\,\mathrm{nnz}_q\,\sigma_q}{R_q'}
          + [q\ \mathrm{sparse}]\, c_e\, S_{\mathrm{src}_q} \sigma_q\Big)
      + \frac{\sum_{\mathrm{driven}} L\,S_p}{R_{upd}}

with ``S_p`` the population sizes (sources included: encoding, state and
bookkeeping cost :data:`CLOSED_NEURON_S` per neuron), ``σ_q`` the spikes per source
neuron (one for latency codes and fire-once neurons), a stencil's ``N_q K_q`` taps
over its target map at :data:`STENCIL_OPS_PER_S`, a matrix's synapse instances at
:data:`BLAS_OPS_PER_S` (dense weights, weighted deliveries: one BLAS product) or
at the gathering rate ``SYNAPSE_OPS_PER_S`` (sparse or delayed weights, or a
target solved by the driven path), plus :data:`CLOSED_EVENT_S` per spike for the
one-hot products of sparse matrices, and the driven spans (the step engine's
own recurrences, ``L`` steps of ``S_p`` neurons) at ``NEURON_UPDATES_PER_S``.
Stencils and sparse matrices into a *gated* population (the OS-CFAR neurons,
:mod:`backends.reference.gate`) count twice: its solver reads them once for the
weight arrived by the gate's step and once for the totals.

The constants were measured on the 2-core development machine (see
``benchmarks/closed_scaling.py`` and ``docs/reliability.md``); the model is meant
to be within a small factor, not a bound.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, NeuronParams,
...                           Population, SpikingNetwork)
>>> net = SpikingNetwork(name="n", n_steps=10,
...     populations=[Population(id="a", shape={"i": 4}, source=True),
...                  Population(id="b", shape={"o": 2},
...                             params=NeuronParams(du=0.0, reset="fire_once"))],
...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
...                                   produce=("o",), weights=np.ones((4, 2)))],
...     encoders=[Encoder(port="x", population="a",
...                       code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))])
>>> [kind for _, kind in span_kinds(net, "b")]  # input and spiking on, du = 0
['driven']
>>> round(closed_time_per_frame(net) * 1e9)  # 60 x 6 neurons + 10 x 2 / 2e8 + 8 / 1e9
468
"""

from __future__ import annotations

from math import prod

from compiler.snn.network import SpikingNetwork
from compiler.snn.projections import MatrixProjection, StencilProjection

__all__ = ["BLAS_OPS_PER_S", "CLOSED_EVENT_S", "CLOSED_NEURON_S", "NEURON_UPDATES_PER_S",
           "STENCIL_OPS_PER_S", "SYNAPSE_OPS_PER_S", "closed_time_per_frame", "span_kinds",
           "spikes_per_neuron"]

#: Vectorised neuron updates per second (one core, numpy): the step engine, driven spans.
NEURON_UPDATES_PER_S = 2e8
#: Synaptic multiply-adds per second through gathers or sparse products (one core).
SYNAPSE_OPS_PER_S = 1e9
#: Multiply-adds per second of a dense BLAS product (the closed form's weighted deliveries).
BLAS_OPS_PER_S = 4e9
#: Stencil taps per second over a whole map (shifted views: compare, add, a few passes).
STENCIL_OPS_PER_S = 5e8
#: Closed form, per neuron and frame of every population: encoding, state, solving, counts.
CLOSED_NEURON_S = 60e-9
#: Closed form, per spike through a sparse matrix: its one-hot row in a CSR product.
CLOSED_EVENT_S = 120e-9


def spikes_per_neuron(network: SpikingNetwork, pid: str) -> float:
    """Spikes one neuron of ``pid`` sends in a frame (an estimate).

    One for latency codes and fire-once neurons, ``max_rate · T`` for rate codes,
    ``T / 2`` for neurons that may fire repeatedly.
    """
    pop = network.population[pid]
    if pop.source:
        enc = next((e for e in network.encoders if e.population == pid), None)
        if enc is not None and enc.code.type == "rate":
            return enc.code.max_rate * network.n_steps
        return 1.0
    return 1.0 if pop.params.reset == "fire_once" else network.n_steps / 2


def _gate_shaped(network: SpikingNetwork, pid: str) -> bool:
    """One matrix and any stencils into ``pid`` (the gated solver's structure, weights unread)."""
    roles = [_GATE_ROLE.get(type(q)) for q in network.projections if q.target == pid]
    return roles.count("matrix") == 1 and None not in roles


def span_kinds(network: SpikingNetwork, pid: str) -> list[tuple[int, str]]:
    """``(steps, kind)`` of each phase span of ``pid`` as the closed form solves it.

    Kinds follow :func:`backends.reference.closed._solve`: ``charge`` (input off,
    ``dv = 0``), ``silent`` (input on, spiking off, ``dv = 0``, ``du`` 0 or 1),
    ``gated`` (integrate-and-fire without leak or bias into a gate-shaped input),
    else ``driven``.  Read from the phases only: no per-step schedule is built.
    """
    params, n_steps = network.population[pid].params, network.n_steps
    starts = [ph.start_step for ph in params.phases] + [n_steps]
    out = []
    for ph, start, stop in zip(params.phases, starts, starts[1:], strict=False):
        if start >= n_steps:
            continue
        steps = min(stop, n_steps) - start
        if not ph.input_on and params.dv == 0.0:
            kind = "charge"
        elif (ph.input_on and not ph.spiking_on and params.dv == 0.0
              and params.du in (0.0, 1.0)):
            kind = "silent"
        elif (ph.input_on and ph.spiking_on and params.du == 1.0 and params.dv == 0.0
              and ph.bias == 0 and _gate_shaped(network, pid)):
            kind = "gated"
        else:
            kind = "driven"
        out.append((steps, kind))
    return out


def closed_time_per_frame(network: SpikingNetwork) -> float:
    """Estimated closed-form seconds per frame of ``network`` (see the module for the model).

    Parameters
    ----------
    network : SpikingNetwork
        A network the closed form can run (sizes and phases are read).

    Returns
    -------
    float
    """
    by_id = network.population
    driven_steps, kinds = 0, {}
    for pop in network.populations:
        if not pop.source:
            kinds[pop.id] = span_kinds(network, pop.id)
            driven_steps += sum(steps for steps, k in kinds[pop.id] if k == "driven") * pop.size
    t = CLOSED_NEURON_S * sum(p.size for p in network.populations)
    t += driven_steps / NEURON_UPDATES_PER_S
    for q in network.projections:
        src, tgt = by_id[q.source], by_id[q.target]
        spikes = spikes_per_neuron(network, q.source)
        target_kinds = {k for _, k in kinds[q.target]}
        passes = 2 if "gated" in target_kinds else 1  # by-arrival weights, then totals
        t += _DELIVERY_TIME[type(q)](q, src, tgt, spikes, passes, target_kinds)
    return t


def _stencil_time(q, src, tgt, spikes: float, passes: int, target_kinds: set) -> float:
    return passes * tgt.size * q.n_taps * spikes / STENCIL_OPS_PER_S


def _matrix_time(q, src, tgt, spikes: float, passes: int, target_kinds: set) -> float:
    reps = src.size // max(1, prod(src.shape[a] for a in q.contract))
    ops = reps * int(q.n_synapses) * spikes
    if q.weights is None or q.delays is not None:  # sparse: CSR one-hot products
        return passes * (ops / SYNAPSE_OPS_PER_S + CLOSED_EVENT_S * src.size * spikes)
    return ops / (SYNAPSE_OPS_PER_S if "driven" in target_kinds else BLAS_OPS_PER_S)


#: Closed-form delivery time by projection type (the solver's own costs; explicit table).
_DELIVERY_TIME = {MatrixProjection: _matrix_time, StencilProjection: _stencil_time}

#: The gated solver's role of each projection type: one matrix and any stencils.
_GATE_ROLE = {MatrixProjection: "matrix", StencilProjection: "stencil"}
