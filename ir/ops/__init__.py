"""The op families of the radar DSP IR and the default op registry.

``OP_REGISTRY`` maps each op name (the ``op`` field in chain files) to its class.
It is an ordinary dict: pass an extended copy wherever a ``registry`` is accepted
to add ops, e.g. ``{**OP_REGISTRY, "my_op": MyOp}``.

Examples
--------
>>> {"adc_input", "cfar", "dft", "cluster", "track"} <= set(OP_REGISTRY)
True
>>> OP_REGISTRY["window"] is Window
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

__all__ = [
    "CFAR",
    "CLUSTER_FEATURES",
    "DFT",
    "OP_REGISTRY",
    "TRACK_STATE",
    "Add",
    "AdcInput",
    "CfarWindow",
    "Classifier",
    "Cluster",
    "EdgeMode",
    "Input",
    "Linear",
    "Log",
    "Magnitude",
    "MagnitudeKind",
    "Op",
    "OpRegistry",
    "Output",
    "Sum",
    "Threshold",
    "Track",
    "Window",
    "WindowKind",
    "make_registry",
]

OpRegistry = dict[str, type[Op]]
"""Op name -> op class."""


def make_registry(*op_classes: type[Op]) -> OpRegistry:
    """A registry keyed by each class's ``op`` name.

    Examples
    --------
    >>> make_registry(Window, Sum)
    {'window': <class 'ir.ops.linear.Window'>, 'sum': <class 'ir.ops.linear.Sum'>}
    """
    return {cls.op_name(): cls for cls in op_classes}


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
