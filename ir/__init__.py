"""radarsnn's radar DSP graph IR: typed ops, graphs, chain files and the reference interpreter.

Examples
--------
>>> import numpy as np
>>> from ir import Graph, evaluate
>>> g = Graph.from_yaml('''
... name: tiny-range
... nodes:
...   - {id: x, op: input, shape: {sample: 8}}
...   - {id: rng, op: dft, input: x, axis: sample, out_axis: range, keep: positive}
...   - {id: mag, op: magnitude, input: rng}
...   - {id: out, op: output, input: mag}
... ''')
>>> g.infer_types()["out"]
TensorType(axes={'range': 4}, complex=False, domain='amplitude')
>>> evaluate(g, {"x": np.ones(8)})["out"].tolist()
[8.0, 0.0, 0.0, 0.0]

Only the errors are imported with the package; every other name is imported on first
use (PEP 562 ``__getattr__``).  The error hierarchy is the bottom layer every package
imports (:mod:`radar` included), so ``import ir.errors`` must not load the graph, the
ops and the interpreter — which themselves import :mod:`radar`
(``tests/test_layers.py``).  The op classes are not listed here: they are the classes
of :data:`ir.ops.OP_REGISTRY`, so ``ir.Window`` and ``__all__`` follow the registry.

>>> import ir
>>> ir.Track is ir.OP_REGISTRY["track"], "Cluster" in ir.__all__
(True, True)
"""

# ruff: noqa: F401  (the names are re-exported through __all__, built on first use below)
from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

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

if TYPE_CHECKING:  # what the lazy names are, for type checkers and readers
    from ir.graph import Graph
    from ir.interpreter import EVAL_REGISTRY, EvalRegistry, Implementation, check_input, evaluate
    from ir.ops import *  # noqa: F403  (the op classes of OP_REGISTRY, and its helpers)
    from ir.schema import chain_file_model, chain_schema
    from ir.serialize import (
        graph_from_dict,
        graph_from_json,
        graph_from_yaml,
        graph_to_dict,
        graph_to_json,
        graph_to_yaml,
    )
    from ir.types import DOMAINS, Domain, TensorType

#: Lazy name -> the module that defines it.
_LAZY = {
    **dict.fromkeys(("EVAL_REGISTRY", "EvalRegistry", "Implementation", "check_input",
                     "evaluate"), "ir.interpreter"),
    "Graph": "ir.graph",
    **dict.fromkeys(("OP_REGISTRY", "Op", "OpRegistry", "make_registry"), "ir.ops"),
    **dict.fromkeys(("chain_file_model", "chain_schema"), "ir.schema"),
    **dict.fromkeys(("graph_from_dict", "graph_from_json", "graph_from_yaml", "graph_to_dict",
                     "graph_to_json", "graph_to_yaml"), "ir.serialize"),
    **dict.fromkeys(("DOMAINS", "Domain", "TensorType"), "ir.types"),
}


#: The names imported with the package.
_ERRORS = ("ArtifactError", "BudgetError", "ChainFileError", "CompileError", "IRError",
           "NetworkError", "RadarConfigError", "RadarSNNError", "SimulationError")


def _op_names() -> list[str]:
    """The class names of :data:`ir.ops.OP_REGISTRY` (imports the ops)."""
    from ir.ops.registry import op_classes  # lazy: the ops import radar, which imports ir.errors

    return list(op_classes(import_module("ir.ops").OP_REGISTRY))


def __getattr__(name: str):
    """Import a lazy name's module on first use (PEP 562) and keep the name here.

    ``__all__`` is built on first use too: the errors, the lazy names and the op
    classes of :data:`ir.ops.OP_REGISTRY`.
    """
    if name == "__all__":
        value = [*_ERRORS, *_LAZY, *_op_names()]
    elif name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
    elif name[:1].isupper() and name in _op_names():
        value = getattr(import_module("ir.ops"), name)
    else:
        raise AttributeError(f"module 'ir' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | set(_op_names()))
