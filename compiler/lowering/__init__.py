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
from compiler.lowering.cfar import register_cfar
from compiler.lowering.classifier import register_classifier
from compiler.lowering.context import LoweringContext, lower_graph
from compiler.lowering.dft_fft import register_fft
from compiler.lowering.dft_rate import register_rate
from compiler.lowering.dft_time import register_time
from compiler.lowering.inputs import register_io
from compiler.lowering.registry import HOST, LoweringRegistry, LoweringRule
from compiler.lowering.resonator import register_resonator
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
    register_cfar(registry)
    register_rate(registry)
    register_fft(registry)
    register_time(registry)
    register_resonator(registry)
    register_classifier(registry)
    return registry
