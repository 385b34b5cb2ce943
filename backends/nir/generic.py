r"""A NIR graph from another tool as a :class:`~compiler.snn.SpikingNetwork` (the subset).

The inverse of :mod:`backends.nir.neurons` for forward Euler with step ``dt``
(``radarsnn_dt_s`` metadata, else the ``dt_s`` argument):

==========================================  ============================================
NIR                                         radarsnn
==========================================  ============================================
``Input`` (any shape, flattened)            source population ``{"i": n}``, rate code
                                            (a value in [0, 1] = spikes per step)
``IF``                                      ``du = 1, dv = 0``, input gain ``r·dt``
``LIF``                                     ``dv = dt/tau``, gain ``dv·r``, bias ``dv·v_leak``
``CubaLIF``                                 ``du = dt/tau_syn``, ``dv = dt/tau_mem``, gain
                                            ``du·w_in·dv·r``, bias ``dv·v_leak``
``I`` / ``LI`` feeding one ``IF``/``LIF``   its current stage: ``du = 0`` (gain ``r·dt``) /
                                            ``du = dt/tau`` (gain ``du·r``, ``v_leak = 0``)
``Linear`` / ``Affine`` (``Delay`` before)  a matrix projection (delay ``delay/dt`` steps),
                                            the target's gain folded into the weights; an
                                            ``Affine`` bias into the target's bias (``du = 1``)
an edge neuron → neuron                     identity weights
``Output``                                  a ``count`` decoder
==========================================  ============================================

``v_threshold`` becomes ``nextafter(v_threshold, +inf)`` (NIR fires on ``>``), the
reset is ``value`` to ``v_reset``.  Parameters must be uniform within a node; any
other node or pattern is an :class:`IRError` naming it.

Examples
--------
>>> import nir, numpy as np
>>> g = nir.NIRGraph.from_list(nir.Linear(weight=np.full((1, 2), 0.5)),
...     nir.IF(r=np.full(1, 2.0), v_threshold=np.ones(1), v_reset=np.zeros(1)))
>>> net = import_generic(g, dt_s=1.0, n_steps=4)
>>> net.projections[0].weights.ravel().tolist(), net.populations[1].params.du
([1.0, 1.0], 1.0)
"""

from __future__ import annotations

import nir
import numpy as np

from compiler.snn import (
    Decoder,
    Encoder,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
)
from ir.errors import IRError, RadarSNNError

__all__ = ["import_generic"]

_SPIKING = (nir.IF, nir.LIF, nir.CubaLIF)
_CURRENT = (nir.I, nir.LI)


def _fail(name: str, message: str) -> IRError:
    return IRError(f"NIR node {name!r}: {message}", node=name)


def _one(name: str, node: nir.NIRNode, field: str) -> float:
    values = np.asarray(getattr(node, field), dtype=np.float64).ravel()
    if values.size == 0 or not np.all(values == values[0]) or not np.isfinite(values[0]):
        raise _fail(name, f"{type(node).__name__}.{field} must be one finite value for the "
                          f"whole node, got {np.unique(values)[:4].tolist()}")
    return float(values[0])


def _size(name: str, node: nir.NIRNode) -> int:
    types = node.output_type if isinstance(node, nir.Input) else node.input_type
    shape = next(iter(types.values()), None) if isinstance(types, dict) else None
    if shape is None:
        raise _fail(name, "has no shape")
    return int(np.prod(np.asarray(shape, dtype=np.int64)))


def _params(name: str, node: nir.NIRNode, stage: tuple[str, nir.NIRNode] | None, dt: float
            ) -> tuple[NeuronParams, float]:
    """The population's parameters and the gain folded into its incoming weights."""
    bias = 0.0
    if isinstance(node, nir.IF):
        du, dv, gain = 1.0, 0.0, _one(name, node, "r") * dt
    elif isinstance(node, nir.LIF):
        dv = dt / _one(name, node, "tau")
        du, gain, bias = 1.0, dv * _one(name, node, "r"), dv * _one(name, node, "v_leak")
    else:  # CubaLIF
        du, dv = dt / _one(name, node, "tau_syn"), dt / _one(name, node, "tau_mem")
        gain = du * _one(name, node, "w_in") * dv * _one(name, node, "r")
        bias = dv * _one(name, node, "v_leak")
    if stage is not None:
        sname, snode = stage
        if isinstance(snode, nir.I):
            du, gain = 0.0, gain * _one(sname, snode, "r") * dt
        else:
            if _one(sname, snode, "v_leak") != 0.0:
                raise _fail(sname, "an LI current stage needs v_leak = 0")
            du = dt / _one(sname, snode, "tau")
            gain *= du * _one(sname, snode, "r")
    if not (0.0 <= du <= 1.0 and 0.0 <= dv <= 1.0):
        raise _fail(name, f"time constants give decays d_u = {du:g}, d_v = {dv:g} outside "
                          f"[0, 1] at dt = {dt:g} s; pass a smaller dt_s")
    v_th = float(np.nextafter(_one(name, node, "v_threshold"), np.inf))
    try:
        params = NeuronParams(du=du, dv=dv, v_th=v_th, reset="value",
                              v_reset=_one(name, node, "v_reset"),
                              phases=(Phase(start_step=0, bias=bias),))
    except ValueError as exc:
        raise _fail(name, f"has no radarsnn neuron form ({str(exc).splitlines()[-1]})") from None
    return params, gain


def import_generic(graph: nir.NIRGraph, *, dt_s: float | None = None, n_steps: int = 100,
                   name: str = "nir") -> SpikingNetwork:
    """Read a NIR graph of the subset above as one spiking network.

    Parameters
    ----------
    graph : nir.NIRGraph
    dt_s : float, optional
        The step, when the graph has no ``radarsnn_dt_s`` metadata.
    n_steps : int
        Steps of one run (NIR graphs have no window).
    name : str
        The network's name.

    Returns
    -------
    SpikingNetwork
        Validated; populations and decoders named after the NIR nodes.

    Raises
    ------
    IRError
        For a node or pattern outside the subset, naming the NIR node.
    """
    meta = graph.metadata if isinstance(graph.metadata, dict) else {}
    dt = meta.get("radarsnn_dt_s", dt_s)
    try:
        dt = float(dt.decode() if isinstance(dt, bytes) else dt)
    except (TypeError, ValueError):
        raise IRError(f"NIR graph {name!r}: no step duration: pass dt_s (--dt-s) for a graph "
                      "without radarsnn_dt_s metadata") from None
    if not (np.isfinite(dt) and dt > 0):
        raise IRError(f"NIR graph {name!r}: dt_s must be a positive number, got {dt}")
    nodes = graph.nodes
    preds = {k: [a for a, b in graph.edges if b == k] for k in nodes}
    succ = {k: [b for a, b in graph.edges if a == k] for k in nodes}
    pops, params, entry = [], {}, {}
    for key, node in nodes.items():
        if isinstance(node, nir.Input):
            pops.append(Population(id=key, shape={"i": _size(key, node)}, source=True))
        elif isinstance(node, _SPIKING):
            stages = [p for p in preds[key] if isinstance(nodes[p], _CURRENT)]
            if len(stages) > 1 or (stages and preds[key] != stages):
                raise _fail(key, "takes a current stage (I/LI) as its only input, or none")
            stage = (stages[0], nodes[stages[0]]) if stages else None
            params[key] = _params(key, node, stage, dt)
            entry[stages[0] if stages else key] = key
            pops.append(Population(id=key, shape={"i": _size(key, node)},
                                   params=params[key][0]))
        elif isinstance(node, _CURRENT) and not (
                len(succ[key]) == 1 and isinstance(nodes[succ[key][0]], _SPIKING)):
            raise _fail(key, f"a {type(node).__name__} must feed exactly one IF/LIF (its "
                             "current stage); a non-spiking readout has no radarsnn form")
    sizes = {p.id: p.size for p in pops}
    projections, decoders = [], []
    for key, node in nodes.items():
        if isinstance(node, (nir.Linear, nir.Affine)):
            (head,) = preds[key] if len(preds[key]) == 1 else (None,)
            delay = 0
            if head is not None and isinstance(nodes[head], nir.Delay):
                steps = np.asarray(nodes[head].delay, dtype=np.float64).ravel() / dt
                if steps.size == 0 or np.any(steps != np.round(steps[0])) or steps[0] < 1:
                    raise _fail(head, f"delays {np.unique(steps)[:4].tolist()} steps must be "
                                      "one whole number >= 1 of dt")
                delay, (head,) = int(steps[0]), preds[head] if len(preds[head]) == 1 else (None,)
            if head not in sizes or not succ[key] or any(t not in entry for t in succ[key]):
                raise _fail(key, "a Linear/Affine must read one Input or spiking node (through "
                                 "at most one Delay) and feed neurons")
            w = np.asarray(node.weight, dtype=np.float64)
            for t in succ[key]:
                target = entry[t]
                p, gain = params[target]
                if w.shape != (sizes[target], sizes[head]):
                    raise _fail(key, f"weight shape {w.shape} is not ({sizes[target]}, "
                                     f"{sizes[head]})")
                if isinstance(node, nir.Affine) and np.any(np.asarray(node.bias) != 0):
                    if p.du != 1.0:
                        raise _fail(key, "an Affine bias into a current stage has no form")
                    b = p.phases[0].bias + gain * _one(key, node, "bias")
                    p = p.model_copy(update={"phases": (Phase(start_step=0, bias=b),)})
                    params[target] = (p, gain)
                projections.append(MatrixProjection(
                    id=f"{key}->{target}", source=head, target=target, contract=("i",),
                    produce=("i",), weights=(w * gain).T,
                    delays=np.full((sizes[head], sizes[target]), delay)))
        elif isinstance(node, nir.Delay):
            if not succ[key] or any(not isinstance(nodes[t], (nir.Linear, nir.Affine))
                                    for t in succ[key]):
                raise _fail(key, "a Delay must feed Linear/Affine nodes only")
        elif isinstance(node, _SPIKING + _CURRENT + (nir.Input,)):
            for t in (t for t in succ[key] if t in entry and key in sizes):
                target, gain = entry[t], params[entry[t]][1]  # neuron -> neuron: identity
                n = sizes[key]
                if n != sizes[target]:
                    raise _fail(key, f"an edge to {t!r} joins {n} to {sizes[target]} neurons; "
                                     "put a Linear between them")
                projections.append(MatrixProjection(
                    id=f"{key}->{target}", source=key, target=target, contract=("i",),
                    produce=("i",), rows=np.arange(n), cols=np.arange(n),
                    values=np.full(n, gain), n_in_out=(n, n)))
        elif isinstance(node, nir.Output):
            if len(preds[key]) != 1 or preds[key][0] not in params:
                raise _fail(key, "an Output must read one spiking node")
            decoders.append(Decoder(port=key, population=preds[key][0], kind="count"))
        else:
            raise _fail(key, f"{type(node).__name__} is outside the NIR subset radarsnn "
                             "imports (docs/interop.md)")
    pops = [p.model_copy(update={"params": params[p.id][0]}) if p.id in params else p
            for p in pops]
    encoders = [Encoder(port=p.id, population=p.id, code=RateCode(max_rate=1.0))
                for p in pops if p.source]
    try:
        return SpikingNetwork(name=name, n_steps=n_steps, populations=pops,
                              projections=projections, encoders=encoders,
                              decoders=decoders).validate()
    except RadarSNNError as exc:
        raise IRError(f"NIR graph {name!r}: {exc}") from None
