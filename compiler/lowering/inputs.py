"""Lowering rules of the graph's inputs: their values arrive on the host."""

from __future__ import annotations

from compiler.lowering.context import LoweringContext
from compiler.lowering.registry import HOST, LoweringRegistry
from compiler.lowering.values import HostValue, Value
from ir.ops import AdcInput, Input, Op

__all__ = ["register_io"]


def _input_on_host(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> Value:
    """A graph input: an array the caller passes at run time (no segment)."""
    return HostValue(node=node, type=ctx.types[node])


def register_io(registry: LoweringRegistry) -> None:
    """Register the input ops (``adc_input``, ``input``): host values, no segment."""
    for op_type in (AdcInput, Input):
        registry.register(op_type, HOST, _input_on_host, default=True)
