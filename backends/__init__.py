"""Backends: the reference simulator (:mod:`backends.reference`) and the artifact formats.

:func:`save` stores a compiled program (:mod:`backends.program_artifact`) or one
spiking network (:mod:`backends.artifact`) on disk; :func:`load` reads either
back, telling them apart by the files in the directory.

Examples
--------
>>> import tempfile
>>> from compiler.snn import Encoder, Population, RateCode, SpikingNetwork
>>> net = SpikingNetwork(name="src", n_steps=4,
...     populations=[Population(id="in", shape={"i": 3}, source=True)],
...     encoders=[Encoder(port="x", population="in", code=RateCode())])
>>> with tempfile.TemporaryDirectory() as tmp:
...     type(load(save(net, tmp))).__name__
'SpikingNetwork'
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from backends import artifact
from backends.arguments import directory_arg
from backends.artifact import ARTIFACT_VERSION
from backends.program_artifact import PROGRAM_VERSION, is_program, load_program, save_program
from compiler.program import CompiledProgram
from compiler.snn import SpikingNetwork
from ir.errors import ArtifactError

__all__ = ["ARTIFACT_VERSION", "PROGRAM_VERSION", "is_program", "load", "load_program", "save",
           "save_program"]


def save(obj: Any, directory: str | Path, **kwargs: Any) -> Path:
    """Save a :class:`~compiler.program.CompiledProgram` or a :class:`~compiler.snn.SpikingNetwork`.

    Keyword arguments go to :func:`backends.program_artifact.save_program` or
    :func:`backends.artifact.save`.
    """

    directory = directory_arg(directory, "save")
    if isinstance(obj, CompiledProgram):
        return save_program(obj, directory, **kwargs)
    if not isinstance(obj, SpikingNetwork):
        raise ArtifactError(f"cannot save a {type(obj).__name__} to {directory}: save() takes a "
                            "CompiledProgram or a SpikingNetwork (chains: Graph.to_yaml)")
    if is_program(directory):  # load() would find the program, not this network
        raise ArtifactError(f"{directory} holds a program artifact (program.json); save the "
                            "network into another directory")
    return artifact.save(obj, directory, **kwargs)


def load(directory: str | Path, **kwargs: Any) -> Any:
    """Load what :func:`save` wrote: a program if ``program.json`` is there, else a network."""
    directory = directory_arg(directory, "load")
    if is_program(directory):
        return load_program(directory)
    return artifact.load(directory, **kwargs)
