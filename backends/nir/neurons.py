r"""One population's neuron model as NIR nodes (discrete time, ``dt`` = one step).

NIR nodes are continuous-time ODEs; we export them for forward-Euler
integration with step ``dt`` (graph metadata ``radarsnn_dt_s``), the current
updated before the voltage in each step and both reading this step's input —
exactly the update of :mod:`compiler.snn.neurons`:

=====================  =========================================================
current stage          ``u[t] = (1 - d_u) u[t-1] + I[t]``
  ``d_u = 1``          none: ``u = I`` (the input reaches the voltage node)
  ``d_u = 0``          ``I`` node (integrator), ``r = 1/dt``
  ``0 < d_u < 1``      ``LI`` node, ``tau = dt/d_u``, ``r = 1/d_u``, ``v_leak = 0``
                       (or, with ``d_v > 0``, one ``CubaLIF``: ``tau_syn = dt/d_u``,
                       ``w_in = 1/d_u``)
voltage stage          ``v[t] = (1 - d_v) v[t-1] + u[t] + b``
  ``d_v = 0``          ``IF``, ``r = 1/dt``
  ``d_v > 0``          ``LIF``, ``tau = dt/d_v``, ``r = 1/d_v``, ``v_leak = b/d_v``
=====================  =========================================================

Euler on ``tau v' = (v_leak - v) + r u`` gives ``v += (dt/tau)(v_leak - v + r u)``,
which with these values is the line above.  NIR spikes on ``v > v_threshold``
and resets to ``v_reset``; our ``v >= v_th`` is exported exactly as
``v_threshold = nextafter(v_th, -inf)`` (no float lies strictly between).

Examples
--------
>>> from compiler.snn import NeuronParams, Phase, Population
>>> from backends.nir.report import ExportReport
>>> pop = Population(id="l/out", shape={"o": 2}, params=NeuronParams(dv=0.5, v_th=1.0,
...                  reset="value", phases=(Phase(start_step=0, bias=0.25),)))
>>> nodes, entry, exit_ = neuron_nodes(pop, "l.out", 1.0, ExportReport())
>>> [type(n).__name__ for n in nodes.values()], entry, exit_
(['LIF'], 'l.out', 'l.out')
>>> float(nodes["l.out"].v_leak[0]), float(nodes["l.out"].tau[0])
(0.5, 2.0)
"""

from __future__ import annotations

import json

import nir
import numpy as np

from backends.nir.report import ExportReport
from compiler.snn.network import Population

__all__ = ["neuron_nodes", "bias_of", "params_json", "origin_node", "scaled_bias"]


def origin_node(item_id: str, origin: dict) -> str:
    """The radar-IR node an item stands for: ``origin["node"]``, else the id's prefix.

    Examples
    --------
    >>> origin_node("rd/out", {}), origin_node("p", {"node": "cfar"})
    ('rd', 'cfar')
    """
    return origin.get("node") or item_id.split("/")[0]


def params_json(pop: Population) -> str:
    """The population's :class:`~compiler.snn.NeuronParams` as a JSON string (for metadata)."""
    return json.dumps(pop.params.model_dump(mode="json"), sort_keys=True)


def bias_of(pop: Population) -> float | None:
    """The constant bias of a single-phase, always-on population, else ``None``.

    Examples
    --------
    >>> from compiler.snn import NeuronParams
    >>> bias_of(Population(id="p", shape={"i": 1}, params=NeuronParams()))
    0.0
    """
    phases = pop.params.phases
    if len(phases) == 1 and phases[0].input_on and phases[0].spiking_on:
        return float(phases[0].bias)
    return None


def _full(pop: Population, value: float) -> np.ndarray:
    return np.full(pop.size, float(value))


def _scaled(pop: Population, value: float) -> np.ndarray:
    """``value`` per neuron times its per-neuron scale (thresholds, resets, biases)."""
    scale = pop.params.scale_of(pop.shape)
    return _full(pop, value) if scale is None else float(value) * scale


def scaled_bias(pop: Population) -> np.ndarray:
    """The constant bias of :func:`bias_of` per neuron (per-neuron scales applied)."""
    return _scaled(pop, bias_of(pop) or 0.0)


def neuron_nodes(
    pop: Population, name: str, dt_s: float, report: ExportReport, bias_elsewhere: bool = False
) -> tuple[dict[str, nir.NIRNode], str, str]:
    """NIR nodes of one neuron population (flat shape ``(size,)``).

    Parameters
    ----------
    pop : Population
        A neuron (not source) population.
    name : str
        The NIR name of its spiking node (current-stage nodes get ``name + ".syn"``).
    dt_s : float
        The step duration.
    report : ExportReport
        Receives one entry per aspect (neuron, threshold, bias, reset, schedule).
    bias_elsewhere : bool
        The caller puts the constant bias on an incoming ``Affine`` (``d_v = 0``, ``d_u = 1``).

    Returns
    -------
    nodes : dict
        The nodes, in input-to-output order.
    entry, exit : str
        The node that receives the synaptic input, and the node that emits spikes.
    """
    p, pid = pop.params, pop.id
    meta = {"radarsnn_population": pid, "radarsnn_node": origin_node(pop.id, pop.origin),
            "radarsnn_motif": pop.origin.get("motif", ""), "radarsnn_params": params_json(pop)}
    bias = bias_of(pop)
    threshold = np.nextafter(_scaled(pop, p.v_th), -np.inf)
    report.add(pid, "threshold", "lowered",
               f"v >= {p.v_th:g} exported as NIR v > nextafter({p.v_th:g}, -inf)")
    if p.reset == "value":
        v_reset = _scaled(pop, p.v_reset)
        report.add(pid, "reset", "exact", f"reset to v_reset = {p.v_reset:g}")
    else:
        v_reset = _full(pop, 0.0)
        what = ("subtraction of v_th" if p.reset == "subtract"
                else "fire-once (one spike per frame, v kept)")
        report.add(pid, "reset", "outside", f"{what} is not a NIR reset; exported as reset "
                   "to 0, the rule is in metadata radarsnn_params")
    leak_bias = bias if (bias is not None and p.dv > 0) else 0.0
    if bias is None:
        report.add(pid, "schedule", "outside",
                   f"{len(p.phases)} phases (bias/input/spiking schedule "
                   f"{[ph.model_dump() for ph in p.phases]}) are time-varying; NIR is "
                   "time-invariant: exported without bias, schedule in radarsnn_params")
    elif bias == 0.0:
        pass
    elif p.dv > 0:
        report.add(pid, "bias", "lowered", f"constant bias {bias:g} as v_leak = b/d_v")
    elif bias_elsewhere:
        report.add(pid, "bias", "lowered", f"constant bias {bias:g} as the bias of an incoming "
                   "Affine (d_u = 1: the input reaches v unfiltered)")
    else:
        report.add(pid, "bias", "outside", f"constant bias {bias:g} into a non-leaky neuron "
                   f"with d_u = {p.du:g} has no NIR form; kept in radarsnn_params")
    nodes: dict[str, nir.NIRNode] = {}
    if 0.0 < p.du < 1.0 and p.dv > 0:
        nodes[name] = nir.CubaLIF(
            tau_syn=_full(pop, dt_s / p.du), tau_mem=_full(pop, dt_s / p.dv),
            r=_full(pop, 1.0 / p.dv), v_leak=_scaled(pop, leak_bias / p.dv),
            v_threshold=threshold, v_reset=v_reset, w_in=_full(pop, 1.0 / p.du), metadata=meta)
        report.add(pid, "neuron", "exact", f"CubaLIF {name}")
        return nodes, name, name
    entry = name
    if p.du == 0.0:
        entry = f"{name}.syn"
        nodes[entry] = nir.I(r=_full(pop, 1.0 / dt_s), metadata={"radarsnn_population": pid})
    elif p.du < 1.0:
        entry = f"{name}.syn"
        nodes[entry] = nir.LI(tau=_full(pop, dt_s / p.du), r=_full(pop, 1.0 / p.du),
                              v_leak=_full(pop, 0.0), metadata={"radarsnn_population": pid})
    if p.dv == 0.0:
        nodes[name] = nir.IF(r=_full(pop, 1.0 / dt_s), v_threshold=threshold, v_reset=v_reset,
                             metadata=meta)
    else:
        nodes[name] = nir.LIF(tau=_full(pop, dt_s / p.dv), r=_full(pop, 1.0 / p.dv),
                              v_leak=_scaled(pop, leak_bias / p.dv), v_threshold=threshold,
                              v_reset=v_reset, metadata=meta)
    kinds = " -> ".join(type(n).__name__ for n in nodes.values())
    report.add(pid, "neuron", "exact" if len(nodes) == 1 else "lowered",
               f"{kinds} ({', '.join(nodes)})")
    return nodes, entry, name

