"""The one exception hierarchy of radarsnn.

Every error the project raises on purpose derives from :class:`RadarSNNError`,
so a caller can catch everything radarsnn refuses with one ``except`` clause and
still tell the kinds apart::

    RadarSNNError
    ├── IRError            a radar DSP graph or chain file is malformed
    │   └── ChainFileError a chain file cannot be read or parsed
    ├── RadarConfigError   a radar configuration, scene or capture is inconsistent
    ├── NetworkError       a spiking network is malformed
    │   └── NetworkValidationError  a network record is built with a bad field value
    ├── CompileError       a graph cannot be compiled as asked
    │   ├── BudgetError    a compiled network does not fit the hardware budget
    │   ├── AccuracyError  no spiking configuration keeps the conventional chain's detections
    │   └── CompileValidationError  a compiler record is built with a bad field value
    ├── SimulationError    a simulation cannot run on the given inputs
    └── ArtifactError      an emitted artifact is missing, truncated, tampered or too new

Messages name the node (or field, or file), what is wrong, the limit and the
amount where there is one, and suggest a fix where one exists.

The two ``...ValidationError`` classes are also pydantic ``ValidationError`` s: a
compiler record (a neuron's parameters, a population, a code, an option model) built
with a bad value raises one, so ``except NetworkError`` and ``except ValidationError``
both catch it, and ``err.errors()`` lists the problems field by field.

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

from typing import Any

# pydantic re-exports this class; pydantic_core alone keeps `radarsnn --version` light
from pydantic_core import ValidationError

__all__ = [
    "RadarSNNError",
    "IRError",
    "ChainFileError",
    "RadarConfigError",
    "NetworkError",
    "NetworkValidationError",
    "CompileError",
    "BudgetError",
    "AccuracyError",
    "CompileValidationError",
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


class _Invalid:
    """A pydantic ``ValidationError`` that reads as one radarsnn message (mixin).

    Pydantic builds the instance (``from_exception_data`` calls the class with its own
    arguments); :meth:`of` then attaches the message that ``str`` shows.
    """

    message: str
    node: str | None

    def __init__(self, *args: Any, **kwargs: Any) -> None:  # pydantic's (title, errors, ...)
        self.message, self.node = "", None

    def __str__(self) -> str:
        return self.message

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.message!r})"

    @classmethod
    def of(cls, err: ValidationError, message: str) -> Any:
        """The error ``err`` (same title and ``errors()``) as this class, reading ``message``.

        Examples
        --------
        >>> from pydantic import BaseModel, ValidationError
        >>> class M(BaseModel):
        ...     n: int
        >>> try:
        ...     M(n="x")
        ... except ValidationError as err:
        ...     typed = NetworkValidationError.of(err, "M: field 'n' is no integer (got 'x')")
        >>> isinstance(typed, NetworkError), isinstance(typed, ValidationError)
        (True, True)
        >>> print(typed)
        M: field 'n' is no integer (got 'x')
        >>> typed.errors(include_url=False)[0]["loc"]
        ('n',)
        """
        return _rebuild(cls, err.title, err.errors(), message)

    def __reduce__(self) -> tuple:  # pickled with its message (sweep workers, copies)
        return _rebuild, (type(self), self.title, self.errors(), self.message)  # type: ignore


def _rebuild(cls: type, title: str, errors: list, message: str) -> Any:
    """An ``_Invalid`` subclass instance of ``title`` and ``errors`` reading ``message``."""
    try:
        new = cls.from_exception_data(title, errors)  # type: ignore[attr-defined]
    except KeyError:  # a validator's own error type (PydanticCustomError): keep its text
        from pydantic_core import PydanticCustomError

        new = cls.from_exception_data(title, [  # type: ignore[attr-defined]
            {**e, "type": PydanticCustomError(e["type"], e["msg"])} for e in errors])
    new.message = message
    new.args = (message,)
    return new


class NetworkValidationError(_Invalid, NetworkError, ValidationError):  # type: ignore[misc]
    """A spiking-network record (neuron parameters, population, code, port) got a bad value.

    Both a :class:`NetworkError` and a pydantic ``ValidationError``; the message names the
    record, each bad field, the rule it breaks and the value given.
    """


class CompileValidationError(_Invalid, CompileError, ValidationError):  # type: ignore[misc]
    """A compiler record (an option model, the accuracy tolerances) got a bad value.

    Both a :class:`CompileError` and a pydantic ``ValidationError``; the message names the
    record, each bad field, the rule it breaks and the value given.
    """


class SimulationError(RadarSNNError):
    """A simulation cannot run: wrong inputs, or a resource limit would be exceeded."""


class ArtifactError(RadarSNNError):
    """An artifact on disk is missing, truncated, tampered with, or from a newer version."""
