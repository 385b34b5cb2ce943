"""The compiler: radar chains in, spiking networks + host segments + resource report out.

:func:`compile_graph` is the entry point (see ``docs/compiler.md``); the
spiking-network IR is :mod:`compiler.snn`, the passes :mod:`compiler.passes`,
the lowering rules :mod:`compiler.lowering`, the hardware profiles
:mod:`compiler.hardware`.  ``compile_graph``, ``CompiledProgram`` and
``Segment`` are imported on first use, so ``import compiler.snn`` stays light.

Examples
--------
>>> import compiler
>>> compiler.compile_graph.__name__
'compile_graph'
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

__all__ = ["CompiledProgram", "Segment", "compile_graph"]

_LAZY = {"compile_graph": "compiler.compile", "CompiledProgram": "compiler.program",
         "Segment": "compiler.program"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'compiler' has no attribute {name!r}")
