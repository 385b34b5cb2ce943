"""The golden numpy meaning of every built-in op, as the interpreter's table.

:data:`EVAL_REGISTRY` (op class -> ``impl(node_id, op, args, types)``) is derived from
:data:`ir.ops.OP_REGISTRY`: each entry is the op class's own reference implementation
(its ``evaluate`` method, :mod:`ir.ops.registry`), which delegates the maths to
:mod:`radar.dsp`, :mod:`radar.cfar`, :mod:`radar.clustering` and :mod:`radar.tracking`,
the golden references the spiking lowerings are checked against.
:mod:`ir.interpreter` runs a graph with it.

Examples
--------
>>> import numpy as np
>>> from ir.ops import Magnitude
>>> EVAL_REGISTRY[Magnitude]("m", Magnitude(), [np.array([3 + 4j])], []).tolist()
[5.0]
>>> sorted(cls.op_name() for cls in EVAL_REGISTRY)[:4]
['add', 'cfar', 'classifier', 'cluster']
"""

from __future__ import annotations

from ir.ops import OP_REGISTRY, Op
from ir.ops.registry import EvalRegistry, Implementation, reference_implementations

__all__ = ["EVAL_REGISTRY", "EvalRegistry", "Implementation"]

EVAL_REGISTRY: dict[type[Op], Implementation] = reference_implementations(OP_REGISTRY)
"""The reference implementation of every op that computes (graph inputs take the given arrays)."""
