"""Lowering: turning radar-IR nodes into spiking motifs (rules registered by op type).

:func:`default_registry` builds the registry the compiler uses; each family of
motifs contributes one ``register_*`` function, called here explicitly.

Examples
--------
>>> reg = default_registry()
>>> reg.describe()["adc_input"]
{'motifs': ['host'], 'default': 'host'}
"""

from compiler.lowering.builder import NetworkBuilder
from compiler.lowering.context import LoweringContext, lower_graph
from compiler.lowering.inputs import register_io
from compiler.lowering.registry import HOST, LoweringRegistry, LoweringRule
from compiler.lowering.values import HostValue, SpikeValue, Value

__all__ = [
    "HOST",
    "HostValue",
    "LoweringContext",
    "LoweringRegistry",
    "LoweringRule",
    "NetworkBuilder",
    "SpikeValue",
    "Value",
    "default_registry",
    "lower_graph",
]


def default_registry() -> LoweringRegistry:
    """The registry of every lowering rule radarsnn ships."""
    registry = LoweringRegistry()
    register_io(registry)
    return registry
