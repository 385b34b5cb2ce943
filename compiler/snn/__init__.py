"""The spiking-network IR the compiler emits (see :mod:`compiler.snn.network`)."""

from compiler.snn.coding import (
    N_PARTS,
    Decoder,
    Encoder,
    LatencyCode,
    PartLayout,
    RateCode,
    combine_parts,
    split_values,
)
from compiler.snn.network import PART_AXIS, Population, SpikingNetwork
from compiler.snn.neurons import DECAY_ONE, NeuronParams, Phase
from compiler.snn.projections import MatrixProjection, Projection, StencilProjection

__all__ = [
    "DECAY_ONE",
    "N_PARTS",
    "PART_AXIS",
    "Decoder",
    "Encoder",
    "LatencyCode",
    "MatrixProjection",
    "NeuronParams",
    "PartLayout",
    "Phase",
    "Population",
    "Projection",
    "RateCode",
    "SpikingNetwork",
    "StencilProjection",
    "combine_parts",
    "split_values",
]
