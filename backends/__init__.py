"""Backends: the reference simulator (:mod:`backends.reference`) and the artifact format.

:func:`save` and :func:`load` store a compiled spiking network on disk and read
it back (see :mod:`backends.artifact`).
"""

from backends.artifact import ARTIFACT_VERSION, load, save

__all__ = ["ARTIFACT_VERSION", "load", "save"]
