"""The resource side of a sweep cell: what the compiled program costs, and what a frame used.

``static_cost`` reads the program (the report's ``totals`` when a target was
compiled for, else the networks themselves); ``run_cost`` adds what one run
measured.  Run counts are additive over frames (``spikes``, ``synaptic_events``,
``clipped`` input values, ``frames``); :func:`finalize_cost` makes them per frame.

Examples
--------
>>> from compiler.compile import compile_graph
>>> from ir import Graph
>>> g = Graph.from_dict({"name": "x", "nodes": [
...     {"id": "a", "op": "input", "shape": {"range": 4}},
...     {"id": "o", "op": "output", "input": "a"}]})
>>> cost = static_cost(compile_graph(g, None))
>>> cost["neurons"], cost["synapses"], cost["steps"], cost["cores"], cost["host_nodes"]
(0, 0, 0, None, 1)
>>> finalize_cost({"spikes": 30, "synaptic_events": 90, "frames": 3})
{'spikes_per_frame': 10.0, 'synaptic_events_per_frame': 30.0, 'clipped_per_frame': 0.0, 'frames': 3}
"""

from __future__ import annotations

from typing import Any

__all__ = ["static_cost", "run_cost", "finalize_cost"]


def static_cost(program) -> dict[str, Any]:
    """Neurons, inputs, synapse instances (and stored), steps, cores and host nodes.

    ``steps`` is the sum of the spiking segments' windows (one frame's time on
    chip when the segments run one after the other); ``cores`` is None without a
    hardware target.
    """
    nets = program.networks
    cost: dict[str, Any] = {
        "neurons": sum(n.n_neurons for n in nets),
        "inputs": sum(n.n_inputs for n in nets),
        "synapses": sum(n.n_synapse_instances() for n in nets),
        "synapses_stored": sum(n.n_synapses for n in nets),
        "steps": sum(n.n_steps for n in nets),
        "cores": None,
        "host_nodes": len(program.host_nodes),
    }
    report = program.records.report
    if report is not None:
        totals = report.data.get("totals", {})
        cost["cores"] = totals.get("cores")
    return cost


def run_cost(result) -> dict[str, int]:
    """Additive counts of one frame's :class:`~backends.reference.program.ProgramResult`."""
    return {"spikes": int(sum(s.total_spikes for s in result.simulations)),
            "synaptic_events": int(sum(s.total_synaptic_events for s in result.simulations)),
            "clipped": int(sum(sum(getattr(s, "clipped", {}).values())
                               for s in result.simulations)),
            "frames": 1}


def finalize_cost(sums: dict[str, int]) -> dict[str, float]:
    """Per-frame spikes and synaptic events from their sums over ``frames`` frames."""
    n = max(int(sums.get("frames", 0)), 1)
    return {"spikes_per_frame": sums.get("spikes", 0) / n,
            "synaptic_events_per_frame": sums.get("synaptic_events", 0) / n,
            "clipped_per_frame": sums.get("clipped", 0) / n,
            "frames": int(sums.get("frames", 0))}
