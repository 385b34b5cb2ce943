"""The op families of the radar DSP IR and the default op registry.

``OP_REGISTRY`` maps each op name (the ``op`` field in chain files) to its class;
it is built here, explicitly, from the op classes of the family modules, and every
list of ops is derived from it (:mod:`ir.ops.registry`), this package's ``__all__``
included.  It is an ordinary dict: pass an extended copy wherever a ``registry`` is
accepted to add ops, e.g. ``{**OP_REGISTRY, "my_op": MyOp}``.

Examples
--------
>>> {"adc_input", "cfar", "dft", "cluster", "track"} <= set(OP_REGISTRY)
True
>>> OP_REGISTRY["window"] is Window
True
>>> "Window" in __all__
True
"""

from __future__ import annotations

from ir.ops.base import Op
from ir.ops.classify import Classifier
from ir.ops.compare import CFAR, CfarWindow, EdgeMode, Threshold
from ir.ops.elementwise import Add, Log, Magnitude, MagnitudeKind
from ir.ops.host import CLUSTER_FEATURES, TRACK_STATE, Cluster, Track
from ir.ops.io import AdcInput, Input, Output
from ir.ops.linear import DFT, Linear, Sum, Window, WindowKind
from ir.ops.registry import OpRegistry, make_registry, op_classes

OP_REGISTRY: OpRegistry = make_registry(
    AdcInput,
    Input,
    Output,
    Window,
    DFT,
    Linear,
    Sum,
    Magnitude,
    Log,
    Add,
    CFAR,
    Threshold,
    Classifier,
    Cluster,
    Track,
)
"""Every op of the IR: op name -> op class."""

# what the package exports besides the op classes, which are derived from OP_REGISTRY
__all__ = ["CLUSTER_FEATURES", "OP_REGISTRY", "TRACK_STATE", "CfarWindow", "EdgeMode",
           "MagnitudeKind", "Op", "OpRegistry", "WindowKind", "make_registry"]
__all__ += op_classes(OP_REGISTRY)
