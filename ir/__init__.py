"""radarsnn's radar DSP graph IR."""

from ir.errors import (
    ArtifactError,
    BudgetError,
    ChainFileError,
    CompileError,
    IRError,
    NetworkError,
    RadarConfigError,
    RadarSNNError,
    SimulationError,
)

__all__ = [
    "ArtifactError",
    "BudgetError",
    "ChainFileError",
    "CompileError",
    "IRError",
    "NetworkError",
    "RadarConfigError",
    "RadarSNNError",
    "SimulationError",
]
