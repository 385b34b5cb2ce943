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
"""

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
from ir.evaluate import EVAL_REGISTRY, EvalRegistry, Implementation, check_input, evaluate
from ir.graph import Graph
from ir.ops import (
    CFAR,
    DFT,
    OP_REGISTRY,
    AdcInput,
    CfarWindow,
    Classifier,
    Input,
    Linear,
    Log,
    Magnitude,
    Op,
    OpRegistry,
    Output,
    Sum,
    Threshold,
    Window,
    make_registry,
)
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

__all__ = [
    # errors
    "ArtifactError",
    "BudgetError",
    "ChainFileError",
    "CompileError",
    "IRError",
    "NetworkError",
    "RadarConfigError",
    "RadarSNNError",
    "SimulationError",
    # types
    "DOMAINS",
    "Domain",
    "TensorType",
    # ops
    "CFAR",
    "DFT",
    "OP_REGISTRY",
    "AdcInput",
    "CfarWindow",
    "Classifier",
    "Input",
    "Linear",
    "Log",
    "Magnitude",
    "Op",
    "OpRegistry",
    "Output",
    "Sum",
    "Threshold",
    "Window",
    "make_registry",
    # graphs and chain files
    "Graph",
    "chain_file_model",
    "chain_schema",
    "graph_from_dict",
    "graph_from_json",
    "graph_from_yaml",
    "graph_to_dict",
    "graph_to_json",
    "graph_to_yaml",
    # reference interpreter
    "EVAL_REGISTRY",
    "EvalRegistry",
    "Implementation",
    "check_input",
    "evaluate",
]
