"""Code emission: a compiled program as a standalone simulator package, one emitter per backend.

:data:`EMITTERS` maps a backend name to its emitter
``emit(source, out_dir, *, name=None, arithmetic="float64") -> Path``; today
``numpy`` (:func:`~backends.emit.numpy_emitter.emit_numpy`).  See ``docs/emit.md``.
"""

from backends.emit.numpy_emitter import emit_numpy

__all__ = ["EMITTERS", "emit_numpy"]

#: Emitters by backend name.
EMITTERS = {"numpy": emit_numpy}
