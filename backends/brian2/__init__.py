"""Brian2 backend: run a compiled spiking network in Brian2 to cross-check the reference.

:func:`simulate_brian2` builds a Brian2 network from a
:class:`~compiler.snn.SpikingNetwork` (neuron equations in Brian2's language,
synapses with delays, schedules as ``TimedArray`` s, encoders as
``SpikeGeneratorGroup`` s) and returns a :class:`~backends.reference.SimResult`.
Brian2 is the optional extra ``brian2``; it is imported only when a simulation
runs.  Modules: :mod:`~backends.brian2.equations` (neuron code),
:mod:`~backends.brian2.synapses` (projections expanded into synapse lists),
:mod:`~backends.brian2.build` (the Brian2 objects and their schedule),
:mod:`~backends.brian2.run` (run and read back), :mod:`~backends.brian2.engine`
(:class:`Brian2Engine`: a whole compiled program through ``run_program``).
"""

from backends.brian2.build import SUB_SLOTS, Brian2Model, build_model
from backends.brian2.engine import Brian2Engine
from backends.brian2.equations import NeuronCode, neuron_code
from backends.brian2.run import TARGETS, import_brian2, read_activity, simulate_brian2
from backends.brian2.synapses import EXPANDERS, SynapseList, dense_weights, expand_projection

__all__ = [
    "EXPANDERS",
    "SUB_SLOTS",
    "TARGETS",
    "Brian2Engine",
    "Brian2Model",
    "NeuronCode",
    "SynapseList",
    "build_model",
    "dense_weights",
    "expand_projection",
    "import_brian2",
    "neuron_code",
    "read_activity",
    "simulate_brian2",
]
