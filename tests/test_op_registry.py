"""Every list of ops is derived from the op registry (issue 32, item 2).

An op's class is its one home: the names ``ir``, ``ir.ops`` and ``radarsnn`` export,
``ir.EVAL_REGISTRY``, the calibration bound rules and the op tables of the docs all
follow :data:`ir.ops.OP_REGISTRY`.  A fake op in a test registry shows up in every
derived list; the docs' tables are checked against the registries.
"""

from __future__ import annotations

import importlib
import inspect
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import ClassVar, Literal

import numpy as np
import pytest

import ir
import ir.ops
import radarsnn
from backends.emit.numpy_host import HOST_EMITTERS
from compiler.calibration_bounds import propagate_bounds
from compiler.lowering import HOST_ONLY
from ir import Graph, evaluate
from ir.implementations import EVAL_REGISTRY
from ir.ops import OP_REGISTRY, Op
from ir.ops.registry import (
    bound_rules,
    no_bound_reasons,
    op_classes,
    op_table,
    reference_implementations,
)
from ir.types import TensorType

DOCS = Path(__file__).resolve().parents[1] / "docs"
FAMILIES = ("classify", "compare", "elementwise", "host", "io", "linear")


class Gain(Op):
    """Multiply by a constant: ``y = g·x``."""

    op: Literal["gain"] = "gain"
    g: float = 2.0

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        return t

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return self.g * args[0]

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """``|g|`` times the bound."""
        return abs(self.g) * bounds[0]


class Probe(Op):
    """A fake graph input without a propagated bound."""

    arity: ClassVar[int] = 0
    no_bound: ClassVar[str] = "a test input: its bound is declared"
    op: Literal["probe"] = "probe"

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        return TensorType(axes={"r": 3})


TEST_REGISTRY = {**OP_REGISTRY, "gain": Gain, "probe": Probe}


# -- the derived lists follow the registry -----------------------------------------------------


def test_a_fake_op_shows_up_in_every_derived_list():
    assert {"Gain", "Probe"} <= set(op_classes(TEST_REGISTRY))
    assert {"Gain", "Probe"}.isdisjoint(op_classes(OP_REGISTRY))
    impls = reference_implementations(TEST_REGISTRY)
    assert Gain in impls and Probe not in impls
    assert impls[Gain]("n", Gain(g=3.0), [np.ones(2)], []).tolist() == [3.0, 3.0]
    rules = bound_rules(TEST_REGISTRY)
    assert rules[Gain] is Gain.bound and Probe not in rules
    assert no_bound_reasons(TEST_REGISTRY)[Probe] == "a test input: its bound is declared"
    rows = op_table(TEST_REGISTRY).splitlines()
    assert ("| `gain` | `Gain` | test_op_registry | `Gain.evaluate` "
            "| `\\|g\\|` times the bound. |") in rows
    assert ("| `probe` | `Probe` | test_op_registry | — (a graph input: its value is given) "
            "| none: a test input: its bound is declared |") in rows
    assert len(rows) == 2 + len(TEST_REGISTRY)


def test_the_fake_op_is_evaluated_and_bounded_from_its_class_alone():
    graph = Graph.from_dict({"name": "g", "nodes": [
        {"id": "x", "op": "input", "shape": {"r": 3}},
        {"id": "y", "op": "gain", "input": "x", "g": -0.5},
        {"id": "o", "op": "output", "input": "y"}]}, registry=TEST_REGISTRY)
    assert evaluate(graph, {"x": np.array([2.0, 4.0, -6.0])})["o"].tolist() == [-1.0, -2.0, 3.0]
    assert propagate_bounds(graph, {"x": 4.0}) == {"x": 4.0, "y": 2.0}


@pytest.mark.parametrize("module", [ir, ir.ops, radarsnn], ids=lambda m: m.__name__)
def test_the_packages_export_exactly_the_registry_ops(module):
    ops = op_classes(OP_REGISTRY)
    exported = {n for n in module.__all__ if isinstance(getattr(module, n), type)
                and issubclass(getattr(module, n), Op) and getattr(module, n) is not Op}
    assert exported == set(ops)
    assert all(getattr(module, n) is cls for n, cls in ops.items())


def test_from_ir_import_star_gives_every_op():
    namespace: dict = {}
    exec("from ir import *", namespace)  # noqa: S102 - the import a user writes
    assert set(op_classes(OP_REGISTRY)) <= set(namespace)
    assert {"Graph", "evaluate", "IRError"} <= set(namespace)


def test_eval_registry_is_derived_from_the_op_classes():
    assert set(EVAL_REGISTRY) == {c for c in OP_REGISTRY.values() if c.has_evaluate()}
    assert {c for c in OP_REGISTRY.values() if not c.has_evaluate()} == {
        OP_REGISTRY["adc_input"], OP_REGISTRY["input"]}


def test_every_op_class_of_the_families_is_in_the_registry():
    """Forgetting the registry entry of a new op class fails here."""
    classes = {cls for family in FAMILIES
               for _, cls in inspect.getmembers(importlib.import_module(f"ir.ops.{family}"),
                                                inspect.isclass)
               if issubclass(cls, Op) and cls is not Op and cls.__module__.startswith("ir.ops.")}
    assert classes == set(OP_REGISTRY.values())


def test_bounds_follow_the_op_classes():
    """Hand-derived: a 4-point DFT of |x| <= 1 is at most 4, an l2 magnitude √2 times that."""
    graph = Graph.from_dict({"name": "b", "nodes": [
        {"id": "a", "op": "input", "shape": {"s": 4}},
        {"id": "f", "op": "dft", "input": "a", "axis": "s"},
        {"id": "m", "op": "magnitude", "input": "f"},
        {"id": "d", "op": "log", "input": "m"},
        {"id": "o", "op": "output", "input": "d"}]})
    out = propagate_bounds(graph, {"a": 1.0})
    assert out["f"] == pytest.approx(4.0) and out["m"] == pytest.approx(4.0 * math.sqrt(2))
    assert "d" not in out and "o" not in out  # log has no bound, and output passes nothing on


# -- the docs' tables are checked against the registries ----------------------------------------


def _section(page: str, heading: str) -> str:
    text = (DOCS / page).read_text()
    start = text.index(f"\n{heading}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else None]


def test_docs_ir_holds_the_derived_op_table():
    assert op_table(OP_REGISTRY) in _section("ir.md", "## Ops")


def test_docs_ir_family_tables_have_one_row_per_op_naming_its_parameters():
    ops = _section("ir.md", "## Ops").split("### ", 1)[1]  # the family tables, after the derived
    rows = re.findall(r"^\| `(\w+)` \|([^\n]*)$", ops, re.M)
    assert sorted(name for name, _ in rows) == sorted(OP_REGISTRY)
    for name, row in rows:
        params = re.split(r"(?<!\\)\|", row)[0]  # the first cell (``\|`` is a literal bar)
        missing = [f for f in OP_REGISTRY[name].model_fields
                   if f != "op" and f"`{f}`" not in params]
        assert not missing, f"docs/ir.md: the {name!r} row does not name {missing}"


def test_docs_emit_lists_the_host_emitters():
    text = (DOCS / "emit.md").read_text()
    sentence = text[text.index("Host segments supported"):].split("Any other host op")[0]
    assert sorted(re.findall(r"`(\w+)`", sentence.split(":", 1)[1])) == sorted(
        cls.op_name() for cls in HOST_EMITTERS)


def test_docs_compiler_lists_the_host_only_ops():
    text = (DOCS / "compiler.md").read_text()
    sentence = text[text.index("says why in `compiler.lowering.HOST_ONLY`"):].split("run on")[0]
    assert sorted(re.findall(r"`(\w+)`", sentence.split("(", 1)[1])) == sorted(
        cls.op_name() for cls in HOST_ONLY)
