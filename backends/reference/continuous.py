r"""Continuous-time closed form of one-layer, fire-once, time-coded networks (no step grid).

The step engines put every latency spike on an integer step.  This engine
takes the same network and evaluates it in **continuous time**: a latency
source spikes at the real time ``t = code.spike_times(x)`` (no rounding; not
at all when ``t >= t_max``), a synapse of delay ``d`` delivers at ``t + d``
(the delays stay the network's integers), and neurons integrate exactly:

``du = 1`` (IF), input always on
    ``v(t) = Σ_{a_j <= t} w_j + ∫_0^t b``; with ``b = 0`` the membrane only
    moves at arrivals.  Arrivals closer than ``tie_steps`` (default ``1e-9``
    step) are **simultaneous**: they are summed before the threshold test, as
    the step engine sums one step's arrivals (a float64 log code rounds its
    times to about ``1e-13`` step, so equal values arrive together).
``du = 0`` (ramp), one input phase then input off
    The first phase ``[0, E)`` has input on and spiking off:
    ``v(E) = Σ_{a_j < E} w_j (E − a_j)``; the later phases have input off, bias
    ``b`` and spiking on: the neuron fires at ``E + max(0, (v_th − v(E))/b)``
    (``b > 0``), or at ``E`` iff ``v(E) >= v_th`` (``b = 0``).  A discrete
    membrane ``v[S]`` at the end of step ``S`` is ``v(S + 1)`` here.

The neuron fires once (``reset="fire_once"``); spike times are real and
``spiked``/``spike_time``/``count`` decoders read them (``spike_time`` with real
``t_s``).  This is the limit of the step engines for infinitely fine steps; it
is what "the spiking CFAR equals the conventional CFAR in continuous time"
means (``tests/test_cfar_spiking.py``).

Examples
--------
Two latency inputs into an IF neuron: the one at ``x = 1`` (time 0) with
weight 2, the one at ``x = 0.5`` (time 2) with weight −1, threshold 1.5.

>>> import numpy as np
>>> from compiler.snn import (Decoder, Encoder, LatencyCode, MatrixProjection,
...                           NeuronParams, Population, SpikingNetwork)
>>> net = SpikingNetwork(name="n", n_steps=8,
...     populations=[Population(id="a", shape={"i": 2}, source=True),
...                  Population(id="b", shape={"o": 1},
...                             params=NeuronParams(du=1.0, v_th=1.5, reset="fire_once"))],
...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
...                                   produce=("o",), weights=np.array([[2.0], [-1.0]]),
...                                   delays=np.array([[1], [0]]))],
...     encoders=[Encoder(port="x", population="a",
...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))],
...     decoders=[Decoder(port="y", population="b", kind="spiked")])
>>> simulate_continuous(net, {"x": np.array([1.0, 0.6])}).outputs["y"].tolist()
[1.0]
>>> simulate_continuous(net, {"x": np.array([1.0, 0.9])}).outputs["y"].tolist()
[0.0]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from compiler.snn import (
    LatencyCode,
    MatrixProjection,
    Population,
    SpikingNetwork,
    StencilProjection,
)
from compiler.snn.coding import N_PARTS, normalize_values, split_values
from ir.errors import SimulationError

__all__ = ["ContinuousResult", "continuous_problems", "simulate_continuous", "TIE_STEPS"]

#: Arrivals closer than this (in steps) are simultaneous.
TIE_STEPS = 1e-9


@dataclass(frozen=True, eq=False)
class ContinuousResult:
    """Outcome of :func:`simulate_continuous`.

    Attributes
    ----------
    outputs : dict of str to ndarray
        Decoded values per port (a leading frames axis iff the inputs had one).
    spike_times : dict of str to ndarray
        Per neuron population, float ``(n_frames, *shape)`` first spike time, NaN = never.
    """

    outputs: dict[str, np.ndarray]
    spike_times: dict[str, np.ndarray]


def continuous_problems(network: SpikingNetwork) -> list[str]:
    """Why :func:`simulate_continuous` cannot run ``network`` (empty when it can).

    Examples
    --------
    >>> from compiler.snn import NeuronParams, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4, populations=[
    ...     Population(id="a", shape={"i": 1}, params=NeuronParams(du=0.5))])
    >>> continuous_problems(net)[0][:40]
    "population 'a': the continuous form need"

    Decoders that divide out per-index gains are left to the step engines:

    >>> from compiler.snn import Decoder
    >>> net = SpikingNetwork(name="n", n_steps=4, populations=[
    ...     Population(id="a", shape={"i": 2}, source=True)], decoders=[
    ...     Decoder(port="y", population="a", kind="count", gain_axis="i", gains=(1.0, 2.0))])
    >>> print(continuous_problems(net)[0])
    decoder 'y': per-index gains along 'i' are not supported in continuous time; \
simulate it with backends.reference.simulate (mode 'step' or 'closed')
    """
    pops = network.population
    out = []
    for p in network.populations:
        if p.source:
            continue
        q, ph = p.params, p.params.phases
        if q.scale_axis is not None:
            out.append(f"population {p.id!r}: per-neuron scales along {q.scale_axis!r} are not "
                       "supported in continuous time; simulate it with "
                       "backends.reference.simulate (mode 'step' or 'closed')")
        elif q.reset != "fire_once" or q.dv != 0.0 or q.du not in (0.0, 1.0):
            out.append(f"population {p.id!r}: the continuous form needs reset='fire_once', "
                       f"dv=0, du in (0, 1); got {q.reset!r}, dv={q.dv}, du={q.du}")
        elif q.du == 1.0 and any(not x.input_on or x.bias != 0.0 for x in ph):
            out.append(f"population {p.id!r}: an IF population (du=1) needs input on and bias 0 "
                       "in every phase")
        elif q.du == 0.0 and (len(ph) < 2 or not ph[0].input_on or ph[0].spiking_on
                              or ph[0].bias != 0.0 or any(x.input_on for x in ph[1:])):
            out.append(f"population {p.id!r}: a ramp population (du=0) needs one input phase "
                       "(spiking off, bias 0) followed by input-off phases")
    for proj in network.projections:
        if not pops[proj.source].source:
            out.append(f"projection {proj.id!r}: source {proj.source!r} is not a spike source; "
                       "the continuous form handles one layer fed by encoders")
    for enc in network.encoders:
        if not isinstance(enc.code, LatencyCode):
            out.append(f"encoder {enc.port!r}: the continuous form needs a latency code")
    for dec in network.decoders:
        if dec.kind == "membrane" or dec.combine != "none":
            out.append(f"decoder {dec.port!r}: kind {dec.kind!r} / combine {dec.combine!r} is "
                       "not supported (use spiked, spike_time or count without combine)")
        if dec.gain_axis is not None:
            out.append(f"decoder {dec.port!r}: per-index gains along {dec.gain_axis!r} are not "
                       "supported in continuous time; simulate it with "
                       "backends.reference.simulate (mode 'step' or 'closed')")
    return out


def _source_times(network: SpikingNetwork, inputs: dict) -> tuple[dict, int, bool]:
    pops = network.population
    times, frames = {}, set()
    for enc in network.encoders:
        if enc.port not in inputs:
            raise SimulationError(f"network {network.name!r}: no input for port {enc.port!r}",
                                  node=enc.port)
        dims = pops[enc.population].dims
        want = dims[:-1] if N_PARTS[enc.split] else dims
        x = np.asarray(inputs[enc.port])
        framed = x.shape != want
        if framed and x.shape[1:] != want:
            raise SimulationError(f"input {enc.port!r}: shape {x.shape}, expected {want} or "
                                  f"(n_frames, *{want})", node=enc.port)
        x = x if framed else x[None]
        names = pops[enc.population].axes[:len(want)]
        x = normalize_values(x, tuple(1 + names.index(a) for a in enc.normalize_axes))
        parts = split_values(x, enc.split).reshape(x.shape[0], -1)
        t = enc.code.spike_times(parts)
        times[enc.population] = np.where(t < min(enc.code.t_max, network.n_steps), t, np.nan)
        frames.add((x.shape[0], framed))
    if len(frames) > 1:
        raise SimulationError(f"network {network.name!r}: inputs disagree on frames {frames}")
    n_frames, framed = frames.pop() if frames else (1, False)
    return times, n_frames, framed


def _matrix_synapses(proj, src: Population, tgt: Population) -> tuple[np.ndarray, ...]:
    """Every synapse instance of a matrix as flat (source index, target index, weight, delay)."""
    w = proj.weights
    if w is not None:
        r, c = np.nonzero(w)
        vals = w[r, c]
        dl = proj.delays[r, c] if proj.delays is not None else np.zeros(r.size, np.int64)
    else:
        r, c, vals = proj.rows, proj.cols, proj.values
        dl = proj.delays if proj.delays is not None else np.zeros(r.size, np.int64)
    reps = [a for a in src.axes if a not in proj.contract]
    rep_dims = [src.shape[a] for a in reps]
    rep_idx = np.indices(rep_dims).reshape(len(reps), int(np.prod(rep_dims)))
    n_rep = int(np.prod(rep_dims))
    ci = np.unravel_index(r, [src.shape[a] for a in proj.contract])
    pi = np.unravel_index(c, [tgt.shape[a] for a in proj.produce])
    s_coord = {**dict(zip(proj.contract, ci, strict=True))}
    t_coord = {**dict(zip(proj.produce, pi, strict=True))}
    s_full = [np.repeat(s_coord[a][None], n_rep, 0) if a in s_coord else
              np.repeat(rep_idx[reps.index(a)][:, None], r.size, 1) for a in src.axes]
    t_full = [np.repeat(t_coord[a][None], n_rep, 0) if a in t_coord else
              np.repeat(rep_idx[reps.index(a)][:, None], r.size, 1) for a in tgt.axes]
    s = np.ravel_multi_index(s_full, src.dims).ravel()
    t = np.ravel_multi_index(t_full, tgt.dims).ravel()
    return s, t, np.tile(vals, n_rep), np.tile(dl, n_rep)


def _stencil_synapses(proj, src: Population, tgt: Population) -> tuple[np.ndarray, ...]:
    """Every synapse instance of a stencil as flat (source index, target index, weight, delay)."""
    taps = np.argwhere(proj.kernel != 0)
    coords = np.indices(tgt.dims).reshape(len(tgt.dims), -1)
    n_tgt = coords.shape[1]
    s_list, t_list, w_list, d_list = [], [], [], []
    radius = proj.radius
    for tap in taps:
        off = {a: int(tap[i]) - radius[i] for i, a in enumerate(proj.axes)}
        ok = np.ones(n_tgt, bool)
        sc = []
        for a, size in tgt.shape.items():
            v = coords[tgt.axes.index(a)] + off.get(a, 0)
            if a in off and proj.edge[proj.axes.index(a)] == "wrap":
                v = v % size
            else:
                ok &= (v >= 0) & (v < size)
            sc.append(v)
        sc = [np.asarray(v)[ok] for v in sc]
        order = [tgt.axes.index(a) for a in src.axes]
        s_list.append(np.ravel_multi_index([sc[i] for i in order], src.dims))
        t_list.append(np.flatnonzero(ok))
        w_list.append(np.full(ok.sum(), proj.kernel[tuple(tap)]))
        d = 0 if proj.delays is None else int(proj.delays[tuple(tap)])
        d_list.append(np.full(ok.sum(), d, np.int64))
    return tuple(np.concatenate(x) for x in (s_list, t_list, w_list, d_list))


#: Synapse expansions by projection type (the solver's own; explicit, no isinstance ladder).
_SYNAPSES = {MatrixProjection: _matrix_synapses, StencilProjection: _stencil_synapses}


def _synapses(proj, src: Population, tgt: Population) -> tuple[np.ndarray, ...]:
    """Every synapse instance as flat (source index, target index, weight, delay)."""
    return _SYNAPSES[type(proj)](proj, src, tgt)


def _solve(network: SpikingNetwork, pop: Population, times: dict, n_frames: int,
           tie_steps: float) -> np.ndarray:
    pops = network.population
    tgt, src_t, wts = [], [], []
    n = pop.size
    for proj in network.incoming(pop.id):
        s, t, w, d = _synapses(proj, pops[proj.source], pop)
        st = times[proj.source][:, s] + d  # (frames, synapses)
        f = np.repeat(np.arange(n_frames), s.size)
        tgt.append(f * n + np.tile(t, n_frames))
        src_t.append(st.ravel())
        wts.append(np.tile(w, n_frames))
    tgt, arr, w = np.concatenate(tgt), np.concatenate(src_t), np.concatenate(wts)
    live = np.isfinite(arr) & (arr < network.n_steps)
    q, ph = pop.params, pop.params.phases
    fire = np.full(n_frames * n, np.nan)
    if q.du == 0.0:
        end = ph[1].start_step
        live &= arr < end
        v = np.bincount(tgt[live], weights=w[live] * (end - arr[live]), minlength=fire.size)
        b = ph[1].bias
        stop = ph[2].start_step if len(ph) > 2 else network.n_steps
        if b > 0:
            at = end + np.maximum(0.0, (q.v_th - v) / b)
        else:
            at = np.where(v >= q.v_th, float(end), np.nan)
        fire = np.where(at < stop, at, np.nan)
        return fire.reshape(n_frames, n)
    tgt, arr, w = tgt[live], arr[live], w[live]
    order = np.lexsort((arr, tgt))
    tgt, arr, w = tgt[order], arr[order], w[order]
    same = np.r_[tgt[1:] == tgt[:-1], False]
    group_end = ~(same & (np.r_[arr[1:], 0.0] - arr <= tie_steps))
    start = np.r_[True, tgt[1:] != tgt[:-1]]
    csum = np.cumsum(w)
    base = np.repeat(csum[start] - w[start], np.diff(np.r_[np.flatnonzero(start), w.size]))
    v = csum - base
    bias, _, spiking = q.schedule(network.n_steps)
    ok_t = spiking[np.minimum(np.floor(arr).astype(np.int64), network.n_steps - 1)]
    hit = group_end & (v >= q.v_th) & ok_t
    first = np.flatnonzero(hit)
    first = first[np.r_[True, tgt[first][1:] != tgt[first][:-1]]] if first.size else first
    fire[tgt[first]] = arr[first]
    return fire.reshape(n_frames, n)


def simulate_continuous(network: SpikingNetwork, inputs: dict, *,
                        tie_steps: float = TIE_STEPS) -> ContinuousResult:
    """Run ``network`` in continuous time (see the module docstring).

    Parameters
    ----------
    network : SpikingNetwork
        One layer of fire-once ``dv = 0`` neurons fed by latency-coded sources.
    inputs : mapping of port to ndarray
        As for :func:`backends.reference.simulate` (value shape, or a frames axis).
    tie_steps : float
        Arrivals at most this far apart (steps) are simultaneous.

    Returns
    -------
    ContinuousResult

    Raises
    ------
    SimulationError
        If the network is outside the continuous form (listing why), or inputs are bad.
    """
    network.validate()
    problems = continuous_problems(network)
    if problems:
        raise SimulationError(f"network {network.name!r} cannot run in continuous time: "
                              + "; ".join(problems))
    times, n_frames, framed = _source_times(network, dict(inputs))
    fire = {p.id: _solve(network, p, times, n_frames, tie_steps)
            for p in network.populations if not p.source}
    pops = network.population
    outputs = {}
    for dec in network.decoders:
        t = fire.get(dec.population, times.get(dec.population))
        if dec.kind == "spike_time":
            y = np.where(np.isnan(t), dec.missing, dec.scale * (dec.t_ref - t) + dec.offset)
        else:
            y = (~np.isnan(t)).astype(np.float64)
            y = dec.scale * y + dec.offset if dec.kind == "count" else y
        y = y.reshape(n_frames, *pops[dec.population].dims)
        outputs[dec.port] = y if framed else y[0]
    spike_times = {pid: t.reshape(n_frames, *pops[pid].dims) for pid, t in fire.items()}
    return ContinuousResult(outputs=outputs, spike_times=spike_times)
