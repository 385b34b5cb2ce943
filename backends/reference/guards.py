r"""Resource guards of the simulator: estimate memory and time before allocating, refuse early.

:func:`estimate_simulation` predicts, from the network's sizes alone, the
dominant memory and wall-clock time of one :func:`~backends.reference.simulate`
call; :func:`check_simulation` refuses a call over its limits with a
:class:`~ir.errors.SimulationError` that states the estimate, the limit and how
to proceed.  The defaults (:data:`MAX_MEMORY_BYTES`, :data:`MAX_TIME_S`) suit a
24 GB, 2-core machine running two simulations side by side.

Memory model (bytes; ``F`` frames, ``S`` sizes of the populations, ``T`` steps,
``s`` the sources, ``q`` the projections with ``R_q`` repetitions of an
``n_in × n_out`` matrix or a target of ``N_q`` neurons):

.. math::

    M = \underbrace{\textstyle 20\sum_q \mathrm{nnz}_q + 32\,T\,|p \notin s|}_{\text{plan:
        CSR per delay, per-step schedules}}
      + F\Big(\underbrace{\textstyle 16\sum_p S_p + 24\sum_{p \notin s} S_p}_{\text{state}}
      + \underbrace{\textstyle 16\sum_{p \in s} S_p}_{\text{trains}}
      + \underbrace{\textstyle \max_q 16\,R_q\,(n_{in} + n_{out})}_{\text{one delivery}}
      + \underbrace{\textstyle 48\sum_{q:\,\mathrm{src}_q \in s} S_{\mathrm{src}_q}}_{\text{step
        mode: trains read ahead}}
      + \underbrace{T\textstyle\sum_p S_p}_{\text{rasters, if recorded}}\Big)

Time model (seconds), step mode: neuron updates at :data:`NEURON_UPDATES_PER_S`
(``F·T·Σ S``), synaptic operations at :data:`SYNAPSE_OPS_PER_S` (every synapse
instance once per source spike: one for latency codes and fire-once neurons, up to
``max_rate·T`` for rate codes and ``T/2`` for neurons that fire repeatedly), plus
:data:`STEP_OVERHEAD_S` per population and step.  Closed form: ``F`` times
:func:`~backends.reference.closed_cost.closed_time_per_frame` (per neuron, per
synapse by delivery path, and only the driven spans per step; the engine is
linear in ``F``).  Both are estimates of the leading terms within a small factor
(measured: ``benchmarks/closed_scaling.py``), not bounds.

Examples
--------
>>> import numpy as np
>>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, NeuronParams,
...                           Population, SpikingNetwork)
>>> net = SpikingNetwork(name="n", n_steps=10,
...     populations=[Population(id="a", shape={"i": 4}, source=True),
...                  Population(id="b", shape={"o": 2}, params=NeuronParams(reset="fire_once"))],
...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
...                                   produce=("o",), weights=np.ones((4, 2)))],
...     encoders=[Encoder(port="x", population="a",
...                       code=LatencyCode(t_max=10, x_min=0.0, x_max=1.0))])
>>> e = estimate_simulation(net, n_frames=1, mode="step")
>>> e.fixed_bytes, e.per_frame_bytes   # 20·8 + 32·10·1 ; 16·6 + 24·2 + 16·4 + 16·1·(4+2) + 48·4
(480, 496)
>>> check_simulation(net, n_frames=10**9, mode="step")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ir.errors.SimulationError: network 'n': simulating 1000000000 frames would take about 496 GB ...
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from backends.reference.closed_cost import (
    NEURON_UPDATES_PER_S,
    SYNAPSE_OPS_PER_S,
    closed_time_per_frame,
    spikes_per_neuron,
)
from compiler.snn.network import SpikingNetwork
from ir.errors import SimulationError
from ir.limits import check_limit, human_bytes  # human_bytes: also exported here

__all__ = ["MAX_MEMORY_BYTES", "MAX_TIME_S", "NEURON_UPDATES_PER_S", "STEP_OVERHEAD_S",
           "SYNAPSE_OPS_PER_S", "SimEstimate", "check_limit", "check_simulation",
           "estimate_simulation", "frames_in", "human_bytes"]

#: Default memory limit of one simulation: 8 GiB (a third of a 24 GB machine).
MAX_MEMORY_BYTES = 8 << 30
#: Default limit on the estimated wall-clock time of one simulation, s.
MAX_TIME_S = 3600.0
#: Python overhead of one population in one step of the step engine, s.
STEP_OVERHEAD_S = 2e-5

_CSR_BYTES = 20        # value 8 + column index 8 + a share of the row pointers and temporaries
_STATE_BYTES = 16      # first spike + spike count, every population
_NEURON_BYTES = 24     # u, v and the current of a neuron population
_TRAIN_BYTES = 16      # a latency train: flat index + step per source value
_SCHEDULE_BYTES = 32   # per step of a neuron population: phase index, bias, input/spike flags
_AHEAD_BYTES = 48      # step mode, per input spike of a train read ahead: ~6 int64 indices
#                        (plus a workspace of at most 1 MiB per projection, not counted)


@dataclass(frozen=True)
class SimEstimate:
    """What one simulation is expected to cost.

    Attributes
    ----------
    fixed_bytes : int
        Memory independent of the batch (the plan's weight operands).
    per_frame_bytes : int
        Memory per frame of the batch (state, trains, a delivery, rasters).
    n_frames : int
        Frames in the batch.
    time_s : float
        Estimated wall-clock time of the whole batch.
    mode : str
        The engine estimated (``step`` or ``closed``).
    """

    fixed_bytes: int
    per_frame_bytes: int
    n_frames: int
    time_s: float
    mode: str

    @property
    def memory_bytes(self) -> int:
        """Estimated peak memory: fixed + frames × per frame."""
        return self.fixed_bytes + self.n_frames * self.per_frame_bytes


def _nnz(proj) -> int:
    return int(proj.n_synapses)


def estimate_simulation(network: SpikingNetwork, n_frames: int, *, mode: str = "step",
                        record_spikes: bool = False) -> SimEstimate:
    """Estimate memory and time of simulating ``n_frames`` frames of ``network``.

    Parameters
    ----------
    network : SpikingNetwork
        The network (sizes are read; nothing is allocated).
    n_frames : int
        Frames in the batch.
    mode : {"step", "closed"}
        The engine that will run.
    record_spikes : bool
        Whether spike rasters are kept.

    Returns
    -------
    SimEstimate
        See the module for the formulas.
    """
    pops = network.populations
    sizes = sum(p.size for p in pops)
    fixed = (sum(_CSR_BYTES * _nnz(q) for q in network.projections)
             + _SCHEDULE_BYTES * network.n_steps * sum(1 for p in pops if not p.source))
    per_frame = (_STATE_BYTES * sizes + _NEURON_BYTES * sum(p.size for p in pops if not p.source)
                 + _TRAIN_BYTES * sum(p.size for p in pops if p.source))
    by_id = network.population
    delivery, synapse_ops = 0, 0.0
    for q in network.projections:
        src, tgt = by_id[q.source], by_id[q.target]
        # a matrix's R (n_in + n_out) is |S| + |T|, as a stencil's is: one rule for every kind
        delivery = max(delivery, 16 * (src.size + tgt.size))
        instances = q.n_synapse_instances(src, tgt)
        synapse_ops += instances * spikes_per_neuron(network, q.source)
        if mode == "step" and src.source:  # the train's currents computed ahead in blocks
            per_frame += _AHEAD_BYTES * src.size
    per_frame += delivery
    if record_spikes:
        per_frame += network.n_steps * sizes
    neurons = sum(p.size for p in pops if not p.source)
    if mode == "closed":
        time_s = n_frames * closed_time_per_frame(network)
    else:
        time_s = (n_frames * (network.n_steps * neurons / NEURON_UPDATES_PER_S
                              + synapse_ops / SYNAPSE_OPS_PER_S)
                  + network.n_steps * len(pops) * STEP_OVERHEAD_S)
    return SimEstimate(fixed_bytes=int(fixed), per_frame_bytes=int(per_frame),
                       n_frames=int(n_frames), time_s=float(time_s), mode=mode)


def check_simulation(network: SpikingNetwork, n_frames: int, *, mode: str = "step",
                     record_spikes: bool = False, max_memory_bytes: int | None = MAX_MEMORY_BYTES,
                     max_time_s: float | None = MAX_TIME_S,
                     closed_eligible: bool = False) -> SimEstimate:
    """Refuse a simulation whose estimate exceeds a limit (``None``: no limit).

    Parameters
    ----------
    network, n_frames, mode, record_spikes
        As for :func:`estimate_simulation`.
    max_memory_bytes : int or None
        Memory limit (default :data:`MAX_MEMORY_BYTES`).
    max_time_s : float or None
        Time limit on the estimate (default :data:`MAX_TIME_S`).
    closed_eligible : bool
        Whether the closed form could run this network (then a step-mode refusal
        suggests it).

    Returns
    -------
    SimEstimate

    Raises
    ------
    SimulationError
        Over a limit: the estimate, the limit, and the ways out (frames per call,
        ``record_spikes=False``, ``mode='closed'``, fewer time steps, a higher limit);
        or a limit that is not a positive finite number or None
        (:func:`ir.limits.check_limit`).
    """
    where = f"network {network.name!r}"
    max_memory_bytes = check_limit("max_memory_bytes", max_memory_bytes, "bytes", where=where)
    max_time_s = check_limit("max_time_s", max_time_s, "s", where=where)
    est = estimate_simulation(network, n_frames, mode=mode, record_spikes=record_spikes)
    if max_memory_bytes is not None and est.memory_bytes > max_memory_bytes:
        room = (max_memory_bytes - est.fixed_bytes) // max(1, est.per_frame_bytes)
        ways = ([f"simulate at most {room} frames per call (split the batch)"] if room >= 1
                else [f"compile with fewer time steps (now {network.n_steps}), neurons or "
                      "synapses"])
        if record_spikes:
            ways.append("use record_spikes=False")
        raise SimulationError(
            f"{where}: simulating {n_frames} frames would take about "
            f"{human_bytes(est.memory_bytes)} (over max_memory_bytes="
            f"{human_bytes(max_memory_bytes)}: {human_bytes(est.fixed_bytes)} fixed + "
            f"{human_bytes(est.per_frame_bytes)} per frame); {', '.join(ways)}, or raise "
            "max_memory_bytes")
    if max_time_s is not None and est.time_s > max_time_s:
        ways = []
        if mode == "step" and closed_eligible:
            closed = estimate_simulation(network, n_frames, mode="closed")
            ways.append(f"use mode='closed' (about {closed.time_s:.3g} s)")
        if n_frames > 1:
            ways.append("simulate fewer frames per call")
        ways.append(f"compile with fewer time steps (now {network.n_steps})")
        raise SimulationError(
            f"{where}: simulating {n_frames} frames in mode={mode!r} would take about "
            f"{est.time_s:.3g} s (over max_time_s={max_time_s:g}); {', '.join(ways)}, or raise "
            "max_time_s")
    return est


def frames_in(network: SpikingNetwork, inputs: Mapping[str, object]) -> int:
    """The batch size the inputs ask for (1 without a frames axis), read from shapes only.

    The inputs are checked later by :func:`~backends.reference.encoding.encode_inputs`;
    this only reads ``shape`` so the guard runs before anything is allocated.

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import Encoder, LatencyCode, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4,
    ...     populations=[Population(id="a", shape={"i": 2}, source=True)],
    ...     encoders=[Encoder(port="x", population="a",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
    >>> frames_in(net, {"x": np.zeros(2)}), frames_in(net, {"x": np.zeros((7, 2))})
    (1, 7)
    """
    n = 1
    pops = network.population
    for enc in network.encoders:
        shape = getattr(inputs.get(enc.port), "shape", ())
        ndim = len(pops[enc.population].dims) - (1 if enc.split != "none" else 0)
        if len(shape) == ndim + 1 and isinstance(shape[0], int):
            n = max(n, shape[0])
    return n
