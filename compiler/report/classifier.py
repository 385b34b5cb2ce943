"""The classifier's row of Vogginger et al.'s Table 3: inputs, neurons, synapses, steps, instances.

Counted on the lowered network of one ``classifier`` node, **per instance** (one ROI
sequence; the batch axes, e.g. ``object``, are instances):

* inputs — the input neurons of one frame (``<node>/input``: ROI cells x levels), the
  spikes the classifier receives per step;
* neurons — every other population of the node (convolutions, OR pools, recurrent LIF,
  integrator);
* synapses — wired synapses of those populations' incoming projections (convolutions
  unrolled, recurrence included; the frame-to-input delay lines excluded);
* steps per frame — network steps over frames (1: one step per radar frame);
* instances per frame — how many objects are classified per radar frame (given).

Examples
--------
>>> row = ClassifierRow(inputs=1024, neurons=3395, synapses=100, steps_per_frame=1,
...                     instances="1-20")
>>> row.as_table_row()
['Object classification (SNN)', '1 024', '3 395', '100', '1', '1-20']
"""

from __future__ import annotations

from dataclasses import dataclass

from compiler.snn import SpikingNetwork

__all__ = ["ClassifierRow", "classifier_row"]


@dataclass(frozen=True)
class ClassifierRow:
    """One Table-3 row (see the module docstring)."""

    inputs: int
    neurons: int
    synapses: int
    steps_per_frame: int
    instances: str

    def as_table_row(self, name: str = "Object classification (SNN)") -> list[str]:
        """The row as strings, thousands separated by thin spaces as in the paper."""
        def fmt(n: int) -> str:
            return f"{n:,}".replace(",", " ")
        return [name, fmt(self.inputs), fmt(self.neurons), fmt(self.synapses),
                str(self.steps_per_frame), self.instances]


def classifier_row(network: SpikingNetwork, node: str, *, frames: int,
                   instances: str = "1-20") -> ClassifierRow:
    """Count the Table-3 row of classifier ``node`` in ``network`` (per instance).

    Parameters
    ----------
    network : SpikingNetwork
        A network holding the lowered node (before or after quantization).
    node : str
        The classifier's node id.
    frames : int
        Frames per sequence (the network runs one step per frame).
    instances : str
        Instances per radar frame, as printed (the paper: ``"1-20"``).

    Returns
    -------
    ClassifierRow
    """
    pops = {p.id: p for p in network.populations if p.origin.get("node") == node}
    relay = pops[f"{node}/input"]
    reps = _batch_size(network, node)
    inner = [p for pid, p in pops.items() if not p.source and pid != relay.id]
    synapses = 0
    for proj in network.projections:
        if proj.target in {p.id for p in inner}:
            synapses += proj.n_synapse_instances(network.population[proj.source],
                                                 network.population[proj.target])
    return ClassifierRow(inputs=relay.size // reps, neurons=sum(p.size for p in inner) // reps,
                         synapses=synapses // reps, steps_per_frame=network.n_steps // frames,
                         instances=instances)


def _batch_size(network: SpikingNetwork, node: str) -> int:
    out = network.population[f"{node}/out"]
    return out.size // out.shape["class"]
