"""Lowering rules, registered by op type and motif name — an explicit object, no import magic.

A *rule* turns one IR node into spiking parts::

    rule(ctx: LoweringContext, node_id: str, op: Op, inputs: list[Value]) -> Value

Each op type may have several motifs (``dft``: ``rate``, ``time``,
``time-fft``); one is the default.  The motif ``host`` is always available:
the node then runs on the host with the reference interpreter's meaning.
Rules are registered on a :class:`LoweringRegistry` instance that is passed
to the compiler; :func:`default_registry` builds the one the compiler uses.

Examples
--------
>>> from ir.ops import Magnitude
>>> reg = LoweringRegistry()
>>> reg.register(Magnitude, "l1", lambda ctx, node, op, inputs: None)
>>> reg.motifs(Magnitude), reg.default_motif(Magnitude)
(['host', 'l1'], 'host')
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ir.errors import CompileError
from ir.ops import Op

if TYPE_CHECKING:
    from compiler.lowering.context import LoweringContext
    from compiler.lowering.values import Value

__all__ = ["LoweringRegistry", "LoweringRule", "HOST"]

LoweringRule = Callable[["LoweringContext", str, Op, list["Value"]], "Value"]

#: The motif name meaning "evaluate this node on the host".
HOST = "host"


class LoweringRegistry:
    """Op type → {motif name → rule}, with one default motif per op type."""

    def __init__(self) -> None:
        self._rules: dict[type[Op], dict[str, LoweringRule]] = {}
        self._defaults: dict[type[Op], str] = {}

    def register(self, op_type: type[Op], motif: str, rule: LoweringRule, *,
                 default: bool = False) -> None:
        """Register ``rule`` as motif ``motif`` of ``op_type`` (the default if asked).

        Registering ``host`` replaces the generic host rule for that op type
        (inputs and outputs do so).
        """
        self._rules.setdefault(op_type, {})[motif] = rule
        if default:
            self._defaults[op_type] = motif

    def lowers(self, op_type: type[Op]) -> bool:
        """Whether any rule is registered for ``op_type`` (beyond the generic host rule)."""
        return bool(self._rules.get(op_type))

    def motifs(self, op_type: type[Op]) -> list[str]:
        """Motif names available for ``op_type`` (always including ``host``)."""
        return sorted({HOST, *self._rules.get(op_type, {})})

    def default_motif(self, op_type: type[Op]) -> str:
        """The motif used when the options do not choose one (``host`` if no rule)."""
        return self._defaults.get(op_type, HOST)

    def rule(self, op_type: type[Op], motif: str, *, node: str = "") -> LoweringRule | None:
        """The rule for ``motif``; None for the generic host rule.

        Raises
        ------
        CompileError
            If ``motif`` is not registered for ``op_type``, listing the ones that are.
        """
        rules = self._rules.get(op_type, {})
        if motif in rules:
            return rules[motif]
        if motif == HOST:
            return None
        name = getattr(op_type, "model_fields", {}).get("op")
        op_name = name.default if name is not None else op_type.__name__
        raise CompileError(
            f"node {node!r} ({op_name}): no motif {motif!r}; available: "
            f"{', '.join(self.motifs(op_type))}", node=node or None)

    def copy(self) -> LoweringRegistry:
        """An independent copy (to add or override rules for one compilation)."""
        new = LoweringRegistry()
        new._rules = {k: dict(v) for k, v in self._rules.items()}
        new._defaults = dict(self._defaults)
        return new

    def describe(self) -> dict[str, Any]:
        """``{op name: {"motifs": [...], "default": ...}}`` for documentation and the CLI."""
        out = {}
        for op_type in self._rules:
            field = getattr(op_type, "model_fields", {}).get("op")
            name = field.default if field is not None else op_type.__name__
            out[name] = {"motifs": self.motifs(op_type), "default": self.default_motif(op_type)}
        return out
