"""The public entry point :func:`simulate`: check, encode, run an engine, decode."""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping

import numpy as np

from backends.reference.closed import closed_form_problems, run_closed
from backends.reference.decoding import check_decoders, decode_outputs
from backends.reference.encoding import encode_inputs
from backends.reference.guards import (
    MAX_MEMORY_BYTES,
    MAX_TIME_S,
    check_simulation,
    frames_in,
)
from backends.reference.input_range import DEFAULT_POLICY
from backends.reference.plan import SimPlan
from backends.reference.plan_cache import cached_plan, peek_plan
from backends.reference.result import Activity, LazyArrays, SimResult, first_steps
from backends.reference.run_options import ENGINE_MODES, RunOptions
from backends.reference.step import run_step
from compiler.snn.network import SpikingNetwork
from ir.errors import SimulationError
from ir.limits import check_limit

__all__ = ["simulate", "ENGINES", "RASTER_LIMIT_BYTES"]

#: Default cap on recorded spike rasters (bytes).
RASTER_LIMIT_BYTES = 256 << 20

log = logging.getLogger(__name__)

#: The engines by mode name (the keys are :data:`~backends.reference.run_options.ENGINE_MODES`).
ENGINES: dict[str, Callable[..., Activity]] = dict(zip(ENGINE_MODES, (run_step, run_closed),
                                                       strict=True))


def simulate(
    network: SpikingNetwork,
    inputs: Mapping[str, np.ndarray],
    *,
    mode: str = "step",
    arithmetic: str = "float64",
    record_spikes: bool = False,
    raster_limit_bytes: int = RASTER_LIMIT_BYTES,
    plan: SimPlan | None = None,
    out_of_range: str | Mapping[str, str] = DEFAULT_POLICY,
    max_memory_bytes: int | None = MAX_MEMORY_BYTES,
    max_time_s: float | None = MAX_TIME_S,
    options: RunOptions | None = None,
) -> SimResult:
    """Simulate a spiking network on a batch of inputs.

    A whole compiled program (spiking and host segments) runs with
    :func:`~backends.reference.program.run_program`, which calls this function for
    each spiking segment with the same :class:`~backends.reference.run_options.RunOptions`.

    Parameters
    ----------
    network : SpikingNetwork
        The network (validated here).
    inputs : mapping of port to ndarray
        One array per encoder port, of the port's value shape (the source
        population's shape without the ``part`` axis a split adds), or with one
        leading frames axis ``(n_frames, *value_shape)`` on every port.
    mode : {"step", "closed", "auto"}
        ``step`` runs every time step; ``closed`` computes the spike steps of a
        fire-once feed-forward network directly; ``auto`` picks ``closed`` when
        the network is eligible.
    arithmetic : {"float64", "int64"}
        Number type of currents and membranes; ``int64`` is fixed-point with
        truncating decays and needs integer parameters.
    record_spikes : bool
        Return full spike rasters in :attr:`SimResult.spikes`.
    raster_limit_bytes : int
        Refuse ``record_spikes`` when the rasters would exceed this many bytes.
    plan : SimPlan, optional
        A plan of ``network`` from :func:`build_plan` to reuse (same arithmetic).  Without
        one, the plan is built on the first call and kept for the next calls on the same
        network (:mod:`backends.reference.plan_cache`).
    out_of_range : {"reject", "warn", "clip"} or mapping of port to it
        Finite input values above an encoder's range
        (:mod:`backends.reference.input_range`): refuse them with a
        ``SimulationError`` naming the port, count, first index and range
        (``reject``, the default), clip them with an ``OutOfRangeWarning``
        (``warn``), or clip them (``clip``); a mapping sets the policy per port
        (ports it leaves out: ``reject``).  Clipped values are counted in
        :attr:`SimResult.clipped`.  NaN/Inf are always refused.
    max_memory_bytes : int or None
        Refuse, before allocating, a run whose estimated memory
        (:mod:`backends.reference.guards`) exceeds this (None: no limit).
    max_time_s : float or None
        Refuse a run whose estimated time exceeds this many seconds (None: no limit).
    options : RunOptions, optional
        All of ``mode``, ``arithmetic``, ``record_spikes``, ``out_of_range``,
        ``max_memory_bytes`` and ``max_time_s`` as one record (it replaces those
        arguments; :mod:`backends.reference.run_options`).

    Returns
    -------
    SimResult
        Decoded outputs (frames axis iff the inputs had one), spike counts,
        synaptic events, first spike steps and optional rasters.

    Raises
    ------
    NetworkError
        If the network does not validate, or a decoder cannot be honoured.
    SimulationError
        For bad inputs (ports, shapes, complex into a real split, NaN/Inf, values
        outside an encoder's range under ``reject``), an unknown mode, arithmetic
        or policy, ``mode="closed"`` on an ineligible network, non-integer
        parameters under ``int64``, rasters over the limit, or an estimated
        memory or time over ``max_memory_bytes`` / ``max_time_s``.

    Notes
    -----
    Both engines follow :mod:`compiler.snn.neurons` to the letter.  They give
    identical spike steps, outputs and counts in ``int64`` always, and in
    ``float64`` whenever every membrane sum is exact (dyadic weights,
    thresholds, biases and times, magnitudes far below ``2**45`` — quantized
    networks); otherwise a neuron whose membrane lands within rounding of its
    threshold may fire one step apart between the modes.

    Examples
    --------
    Two inputs through unit weights into an IF neuron with threshold 2: the
    latency code puts ``x = 1`` at step 0 and ``x = 0.5`` at step 2.

    >>> from compiler.snn import (Decoder, Encoder, LatencyCode, MatrixProjection,
    ...                           NeuronParams, Population, SpikingNetwork)
    >>> net = SpikingNetwork(name="tiny", n_steps=6,
    ...     populations=[Population(id="in", shape={"i": 2}, source=True),
    ...                  Population(id="out", shape={"o": 1},
    ...                             params=NeuronParams(du=0.0, v_th=3.0, reset="fire_once"))],
    ...     projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
    ...                                   produce=("o",), weights=np.ones((2, 1)))],
    ...     encoders=[Encoder(port="x", population="in",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
    ...     decoders=[Decoder(port="t", population="out", kind="spike_time", scale=-1.0)])
    >>> r = simulate(net, {"x": np.array([1.0, 0.5])}, mode="auto")
    >>> r.mode, r.outputs["t"].tolist(), r.synaptic_events
    ('closed', [2.0], {'w': 2})
    """
    if not isinstance(network, SpikingNetwork):
        hint = ("run a compiled program with backends.reference.run_program(program, inputs)"
                if hasattr(network, "segments") else "give a compiler.snn.SpikingNetwork")
        raise SimulationError(f"simulate runs one spiking network, not a "
                              f"{type(network).__name__}; {hint}")
    if options is None:
        options = RunOptions(mode=mode, arithmetic=arithmetic, record_spikes=record_spikes,
                             out_of_range=out_of_range, max_memory_bytes=max_memory_bytes,
                             max_time_s=max_time_s)
    options.checked(f"network {network.name!r}")  # mode, arithmetic, limits
    mode, arithmetic, record_spikes = options.mode, options.arithmetic, options.record_spikes
    out_of_range, max_memory_bytes = options.out_of_range, options.max_memory_bytes
    max_time_s = options.max_time_s
    if not isinstance(inputs, Mapping):
        raise SimulationError(f"network {network.name!r}: inputs must be a mapping of port to "
                              f"array; got {type(inputs).__name__}")
    raster_limit = check_limit("raster_limit_bytes", raster_limit_bytes, "bytes",
                               where=f"network {network.name!r}")
    if plan is None:  # a plan kept from an earlier call on this network (plan_cache)
        plan = peek_plan(network, arithmetic)
    if plan is None:
        network.validate()
        problems = closed_form_problems(network)
    elif plan.network is not network or plan.arithmetic != arithmetic:
        raise SimulationError(f"network {network.name!r}: the plan given was built for network "
                              f"{plan.network.name!r} with arithmetic {plan.arithmetic!r}; build "
                              f"it with build_plan(network, {arithmetic!r})")
    else:  # validated when the plan was built
        problems = list(plan.closed_problems)
    check_simulation(network, frames_in(network, inputs),
                     mode="step" if mode == "step" or problems else "closed",
                     record_spikes=record_spikes, max_memory_bytes=max_memory_bytes,
                     max_time_s=max_time_s, closed_eligible=mode == "step" and not problems)
    if plan is None:
        plan = cached_plan(network, arithmetic)
    check_decoders(network)
    if mode == "closed" and problems:
        raise SimulationError(f"network {network.name!r} cannot use mode='closed': "
                              + "; ".join(problems) + "; use mode='step'")
    run = "step" if mode == "step" or problems else "closed"
    clipped: dict[str, int] = {}
    trains, n_frames, framed = encode_inputs(network, inputs, out_of_range=out_of_range,
                                             clipped=clipped)
    if record_spikes:
        need = n_frames * network.n_steps * sum(p.size for p in network.populations)
        if raster_limit is not None and need > raster_limit:
            raise SimulationError(f"network {network.name!r}: spike rasters would take {need} "
                                  f"bytes ({n_frames} frames x {network.n_steps} steps x "
                                  f"{need // max(1, n_frames * network.n_steps)} neurons), over "
                                  f"raster_limit_bytes={raster_limit_bytes}; simulate fewer "
                                  "frames, raise the limit, or use record_spikes=False")
    log.debug("simulate %r: engine %s, %d frame(s) x %d step(s), %d neuron(s)", network.name,
              run, n_frames, network.n_steps, sum(p.size for p in network.populations))
    act = ENGINES[run](plan, trains, n_frames, record_spikes)
    pops = network.population
    return SimResult(
        outputs=decode_outputs(network, act, framed),
        spike_counts=act.spike_totals(),
        synaptic_events=dict(act.synaptic_events),
        first_spike_steps=LazyArrays({  # in their dtype when read (a source's may be lazy;
            # the closures hold the first spikes only, not the rest of the activity)
            pid: (lambda pid=pid, first=act.first_spike, dims=pops[pid].dims:
                  first_steps(first[pid], network.n_steps, (n_frames, *dims)))
            for pid in act.first_spike}),
        spikes=None if act.rasters is None else {
            pid: r.reshape(n_frames, network.n_steps, *pops[pid].dims)
            for pid, r in act.rasters.items()},
        mode=run,
        arithmetic=arithmetic,
        n_steps=network.n_steps,
        n_frames=n_frames,
        clipped=clipped,
        state_overflow=_overflow(plan, act),
    )


def _overflow(plan, act) -> dict[str, int]:
    """Neuron-steps beyond the chip's state range: the step engine's count, or (closed
    form, which does not step) the final membranes beyond it."""
    limit = plan.state_limit
    if limit is None or act.overflow:
        return dict(act.overflow)
    return {pid: n for pid, v in act.membrane.items()  # counted only past the extremes
            if v.size and (np.fmax.reduce(v, axis=None) > limit  # (fmax, fmin: NaN skipped)
                           or np.fmin.reduce(v, axis=None) < -limit)
            and (n := int(np.count_nonzero(np.abs(v) > limit)))}
