"""Lowering: turning radar-IR nodes into spiking motifs (rules registered by op type).

:func:`default_registry` builds the registry the compiler uses; each family of
motifs contributes one ``register_*`` function, called here explicitly.  An op type
with no rule says why in :data:`HOST_ONLY` (it runs on the host, motif ``host``):
every op of :data:`ir.ops.OP_REGISTRY` is in exactly one of the two
(``tests/test_op_facets.py``).

Examples
--------
>>> reg = default_registry()
>>> reg.describe()["adc_input"]
{'motifs': ['host'], 'default': 'host'}
>>> from ir.ops import Track
>>> reg.lowers(Track), HOST_ONLY[Track][:9]
(False, 'host-only')
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
from ir.ops import Add, Cluster, Log, Op, Output, Sum, Threshold, Track

__all__ = [
    "HOST",
    "HOST_ONLY",
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


#: Op types :func:`default_registry` has no rule for, and why: they run on the host.
HOST_ONLY: dict[type[Op], str] = {
    Output: "marks a graph output: its value is its input's, nothing to lower",
    Sum: "no spiking motif yet: non-coherent integration runs on the decoded values",
    Log: "no spiking motif: decibels are a read-out of decoded values",
    Add: "no spiking motif yet: adds back a part computed apart (the static-split pass)",
    Threshold: "no spiking motif yet: the spiking detector is cfar's",
    Cluster: "host-only: DBSCAN over a detection table",
    Track: "host-only: a stateful Kalman tracker across frames",
}
