"""The one exception hierarchy of radarsnn.

Every error the project raises on purpose derives from :class:`RadarSNNError`,
so a caller can catch everything radarsnn refuses with one ``except`` clause and
still tell the kinds apart::

    RadarSNNError
    ├── IRError            a radar DSP graph or chain file is malformed
    │   └── ChainFileError a chain file cannot be read or parsed
    ├── RadarConfigError   a radar configuration, scene or capture is inconsistent
    ├── NetworkError       a spiking network is malformed
    ├── CompileError       a graph cannot be compiled as asked
    │   ├── BudgetError    a compiled network does not fit the hardware budget
    │   └── AccuracyError  no spiking configuration keeps the conventional chain's detections
    ├── SimulationError    a simulation cannot run on the given inputs
    └── ArtifactError      an emitted artifact is missing, truncated, tampered or too new

Messages name the node (or field, or file), what is wrong, the limit and the
amount where there is one, and suggest a fix where one exists.

Examples
--------
>>> from ir.errors import IRError, RadarSNNError
>>> try:
...     raise IRError("node 'det' (cfar): k=200 is outside 1..176", node="det")
... except RadarSNNError as err:
...     print(err.node, "|", err)
det | node 'det' (cfar): k=200 is outside 1..176
"""

from __future__ import annotations

__all__ = [
    "RadarSNNError",
    "IRError",
    "ChainFileError",
    "RadarConfigError",
    "NetworkError",
    "CompileError",
    "BudgetError",
    "AccuracyError",
    "SimulationError",
    "ArtifactError",
]


class RadarSNNError(Exception):
    """Base class of every error radarsnn raises on purpose.

    Parameters
    ----------
    message : str
        A sentence that says what is wrong, naming the node/field/file.
    node : str, optional
        The id of the graph node (radar IR) or population/projection (spiking
        network) the error is about, for programs that want to point at it.
    """

    def __init__(self, message: str, *, node: str | None = None) -> None:
        super().__init__(message)
        self.node = node


class IRError(RadarSNNError):
    """A radar DSP graph is malformed: bad op parameters, axes, shapes or edges."""


class ChainFileError(IRError):
    """A chain file (YAML/JSON) cannot be read, parsed or mapped onto ops."""


class RadarConfigError(RadarSNNError):
    """A radar configuration, scene description or capture file is inconsistent."""


class NetworkError(RadarSNNError):
    """A spiking network is malformed: shapes, indices, delays or parameters."""


class CompileError(RadarSNNError):
    """A graph cannot be compiled with the options given."""


class BudgetError(CompileError):
    """A compiled network exceeds a hardware budget (neurons, axons, memory, steps)."""


class AccuracyError(CompileError):
    """No spiking configuration keeps what the conventional chain detects (names the stage)."""


class SimulationError(RadarSNNError):
    """A simulation cannot run: wrong inputs, or a resource limit would be exceeded."""


class ArtifactError(RadarSNNError):
    """An artifact on disk is missing, truncated, tampered with, or from a newer version."""
