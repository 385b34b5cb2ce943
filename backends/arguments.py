"""Checks of the arguments the artifact functions take: a directory path, an object to save.

A wrong type is an :class:`~ir.errors.ArtifactError` naming the function, the argument and
what it takes, never a ``TypeError`` from :class:`pathlib.Path` or an ``AttributeError`` deep
in a writer.

Examples
--------
>>> directory_arg("out", "load")
PosixPath('out')
>>> directory_arg(3, "load")
Traceback (most recent call last):
...
ir.errors.ArtifactError: load(directory=3): the directory must be a path (str or \
pathlib.Path), not int
"""

from __future__ import annotations

import os
from pathlib import Path

from ir.errors import ArtifactError
from ir.model import short_repr

__all__ = ["directory_arg", "instance_arg"]


def directory_arg(value: object, call: str) -> Path:
    """``value`` as a :class:`~pathlib.Path`, if it is a ``str`` or an ``os.PathLike`` of one.

    Raises
    ------
    ArtifactError
        Anything else (``None``, a number, bytes, an object).
    """
    if isinstance(value, str | Path) or (isinstance(value, os.PathLike)
                                         and isinstance(os.fspath(value), str)):
        return Path(value)
    raise ArtifactError(f"{call}(directory={short_repr(value)}): the directory must be a path "
                        f"(str or pathlib.Path), not {type(value).__name__}")


def instance_arg(value: object, cls: type, call: str, name: str, hint: str) -> None:
    """Refuse ``value`` unless it is a ``cls`` (``hint``: what to call instead).

    Examples
    --------
    >>> instance_arg(None, int, "save_program", "program", "compile one with compile_graph")
    Traceback (most recent call last):
    ...
    ir.errors.ArtifactError: save_program(program=None): takes a int, not NoneType; compile \
one with compile_graph
    """
    if not isinstance(value, cls):
        raise ArtifactError(f"{call}({name}={short_repr(value)}): takes a {cls.__name__}, not "
                            f"{type(value).__name__}; {hint}")
