"""The reference simulator of radarsnn's spiking networks (see ``docs/simulator.md``).

:func:`simulate` runs a :class:`~compiler.snn.SpikingNetwork` on a batch of
inputs with one of two engines that follow :mod:`compiler.snn.neurons` to the
letter: ``step`` (every time step, vectorized over frames × neurons) and
``closed`` (spike steps of fire-once feed-forward networks computed directly).

Modules: :mod:`~backends.reference.neuron` (the pure step function),
:mod:`~backends.reference.delivery` (spikes → currents per projection kind),
:mod:`~backends.reference.plan` (per-network precomputation),
:mod:`~backends.reference.encoding` / :mod:`~backends.reference.decoding`
(ports), :mod:`~backends.reference.step` and :mod:`~backends.reference.closed`
(engines), :mod:`~backends.reference.result` (:class:`SimResult`).
"""

from backends.reference.checker import ReferenceSimulator
from backends.reference.closed import closed_form_problems
from backends.reference.delivery import DELIVERY_BUILDERS, MatrixDelivery, StencilDelivery
from backends.reference.frames_pool import close_frame_workers
from backends.reference.neuron import NeuronState, StepParams, decay, neuron_step
from backends.reference.plan import SimPlan, build_plan
from backends.reference.program import ProgramResult, program_plans, run_program
from backends.reference.result import SimResult
from backends.reference.run_options import RunOptions
from backends.reference.simulate import RASTER_LIMIT_BYTES, simulate

__all__ = [
    "ReferenceSimulator",
    "DELIVERY_BUILDERS",
    "RASTER_LIMIT_BYTES",
    "MatrixDelivery",
    "NeuronState",
    "ProgramResult",
    "RunOptions",
    "SimPlan",
    "SimResult",
    "StencilDelivery",
    "StepParams",
    "build_plan",
    "close_frame_workers",
    "closed_form_problems",
    "decay",
    "neuron_step",
    "program_plans",
    "run_program",
    "simulate",
]
