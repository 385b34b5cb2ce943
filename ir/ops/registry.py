"""The op registry and every table derived from it: one home per op, the op class.

An op's meaning lives on its class (:class:`~ir.ops.base.Op`): the type rule
(``infer``), the reference implementation (``evaluate``) and the calibration bound
(``bound``, or ``no_bound`` saying why there is none).  A registry maps op names to
op classes (:func:`make_registry`); everything else that lists ops is derived from
one here, so a new op class in the registry shows up everywhere at once:

* :func:`op_classes` — the op class names ``ir``, ``ir.ops`` and ``radarsnn`` export;
* :func:`reference_implementations` — the interpreter's table (``ir.EVAL_REGISTRY``);
* :func:`bound_rules` and :func:`no_bound_reasons` — what the ``calibrate`` pass propagates;
* :func:`op_table` — the table of ops in the documentation (``docs/ir.md``).

Lowering and emission are not the op's meaning; they stay in their own tables
(``compiler.lowering.default_registry``, ``backends.emit.numpy_host``).

Examples
--------
>>> from ir.ops.elementwise import Add, Log
>>> registry = make_registry(Add, Log)
>>> sorted(op_classes(registry))
['Add', 'Log']
>>> list(bound_rules(registry)), no_bound_reasons(registry)[Log][:17]
([<class 'ir.ops.elementwise.Add'>], 'no useful worst c')
>>> import numpy as np
>>> reference_implementations(registry)[Add]("s", Add(), [np.ones(2), np.ones(2)], []).tolist()
[2.0, 2.0]
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable, Mapping

import numpy as np

from ir.ops.base import Op
from ir.types import TensorType

__all__ = ["BoundRule", "EvalRegistry", "Implementation", "OpRegistry", "bound_rule",
           "bound_rules", "make_registry", "no_bound_reasons", "op_classes", "op_table",
           "reference_implementation", "reference_implementations"]

OpRegistry = dict[str, type[Op]]
"""Op name -> op class."""

Implementation = Callable[[str, Op, list[np.ndarray], list[TensorType]], np.ndarray]
"""``impl(node_id, op, input_arrays, input_types) -> output array``."""

EvalRegistry = Mapping[type[Op], Implementation]
"""Op class -> implementation."""

BoundRule = Callable[[str, Op, list[float], list[TensorType]], float]
"""``rule(node_id, op, input_bounds, input_types) -> bound`` of a node whose inputs have one."""


def make_registry(*op_classes: type[Op]) -> OpRegistry:
    """A registry keyed by each class's ``op`` name.

    Examples
    --------
    >>> from ir.ops.linear import Sum, Window
    >>> make_registry(Window, Sum)
    {'window': <class 'ir.ops.linear.Window'>, 'sum': <class 'ir.ops.linear.Sum'>}
    """
    return {cls.op_name(): cls for cls in op_classes}


def op_classes(registry: Mapping[str, type[Op]]) -> dict[str, type[Op]]:
    """Class name -> op class, sorted by name: the op names the packages export.

    Examples
    --------
    >>> from ir.ops.linear import DFT, Sum
    >>> op_classes(make_registry(Sum, DFT))
    {'DFT': <class 'ir.ops.linear.DFT'>, 'Sum': <class 'ir.ops.linear.Sum'>}
    """
    return {cls.__name__: cls for cls in sorted(registry.values(), key=lambda c: c.__name__)}


def reference_implementation(op_type: type[Op]) -> Implementation | None:
    """``op_type.evaluate`` as an implementation ``impl(node_id, op, args, types)``, or None.

    None when the class has no reference implementation (graph inputs, a custom op
    whose meaning is given to the interpreter instead).
    """
    if not op_type.has_evaluate():
        return None
    method = op_type.evaluate

    def implementation(node_id: str, op: Op, args: list[np.ndarray],
                       types: list[TensorType]) -> np.ndarray:
        return method(op, node_id, args, types)

    implementation.__qualname__ = implementation.__name__ = f"{op_type.__name__}.evaluate"
    implementation.__doc__ = method.__doc__
    return implementation


def reference_implementations(registry: Mapping[str, type[Op]]) -> dict[type[Op], Implementation]:
    """Op class -> reference implementation, for every op of ``registry`` that has one."""
    out = {cls: reference_implementation(cls) for cls in registry.values()}
    return {cls: impl for cls, impl in out.items() if impl is not None}


def bound_rule(op_type: type[Op]) -> BoundRule | None:
    """``op_type.bound`` as a rule ``rule(node_id, op, bounds, types)``, or None."""
    return op_type.bound if op_type.has_bound() else None


def bound_rules(registry: Mapping[str, type[Op]]) -> dict[type[Op], BoundRule]:
    """Op class -> calibration bound rule, for every op of ``registry`` that has one."""
    return {cls: cls.bound for cls in registry.values() if cls.has_bound()}


def no_bound_reasons(registry: Mapping[str, type[Op]]) -> dict[type[Op], str]:
    """Op class -> why it has no calibration bound, for every op that says so."""
    return {cls: cls.no_bound for cls in registry.values() if cls.no_bound}


def _markdown(text: str | None) -> str:
    """The first paragraph of a docstring as one Markdown table cell."""
    first = " ".join(inspect.cleandoc(text or "").split("\n\n")[0].split())
    return re.sub(r":\w+:`~?([^`]*)`", r"`\1`", first).replace("``", "`").replace("|", "\\|")


def op_table(registry: Mapping[str, type[Op]]) -> str:
    """The Markdown table of the ops of ``registry``: name, class, family, meaning, bound.

    The family is the class's module under :mod:`ir.ops`; the reference implementation,
    the class's ``evaluate`` (or that the value is given: a graph input); the bound, the
    first paragraph of its ``bound`` docstring, or why it has none.  ``docs/ir.md`` holds
    this table for :data:`ir.ops.OP_REGISTRY` (a test keeps the page equal to it).

    Examples
    --------
    >>> from ir.ops.elementwise import Add
    >>> from ir.ops.io import Input
    >>> print(op_table(make_registry(Add, Input)))
    | op | class | family | reference implementation | calibration bound |
    |---|---|---|---|---|
    | `add` | `Add` | elementwise | `Add.evaluate` | The sum of the two bounds. |
    | `input` | `Input` | io | — (a graph input: its value is given) | none: a graph input: \
bounded by the option input_bounds, not propagated |
    """
    rows = ["| op | class | family | reference implementation | calibration bound |",
            "|---|---|---|---|---|"]
    for name, cls in sorted(registry.items()):
        family = cls.__module__.rsplit(".", 1)[-1]
        meaning = (f"`{cls.__name__}.evaluate`" if cls.has_evaluate()
                   else "— (a graph input: its value is given)")
        if cls.has_bound():
            bound = _markdown(cls.bound.__doc__)
        else:
            bound = f"none: {cls.no_bound}" if cls.no_bound else "none"
        rows.append(f"| `{name}` | `{cls.__name__}` | {family} | {meaning} | {bound} |")
    return "\n".join(rows)
