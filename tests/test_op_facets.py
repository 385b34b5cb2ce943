"""Every op of the IR answers for each per-op facet, or says why it has none (issue 20, item 6).

An op's meaning lives on its class: its reference implementation (``Op.evaluate``) and
its calibration bound (``Op.bound``, or ``Op.no_bound`` saying why there is none); the
tables ``ir.EVAL_REGISTRY`` and the bound rules are derived from the op registry.  What
is not the op's meaning stays in tables outside ``ir``, by op type: its lowering rules
(``default_registry``, or ``compiler.lowering.HOST_ONLY`` saying why there are none), its
host emission in generated packages (``backends.emit.numpy_host``) and its weight matrix
(``op_weights``).  A new op that forgets one of them fails here, naming the table.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import pytest

from backends.emit.numpy_host import HOST_EMITTERS, NOT_EMITTED
from compiler.lowering import HOST_ONLY, LoweringRegistry, default_registry
from compiler.lowering.dft_common import op_weights
from compiler.lowering.registry import HOST
from ir.errors import CompileError
from ir.implementations import EVAL_REGISTRY
from ir.ops import DFT, OP_REGISTRY, Linear, Op, Window
from ir.types import TensorType

OPS = sorted(OP_REGISTRY.items())


def facet_gaps(ops: dict[str, type[Op]], lowering: LoweringRegistry,
               host_only: dict, host_emitters: dict, not_emitted: dict) -> list[str]:
    """One line per facet an op of ``ops`` neither has nor explains, naming the table."""
    gaps = []
    for name, cls in sorted(ops.items()):
        if not cls.has_evaluate() and cls.arity != 0:
            gaps.append(f"{name}: no reference implementation ({cls.__name__}.evaluate)")
        if cls.has_bound() == bool(cls.no_bound):
            gaps.append(f"{name}: neither or both of {cls.__name__}.bound and .no_bound")
        if lowering.lowers(cls) == (cls in host_only):
            gaps.append(f"{name}: in neither or both of the lowering registry and "
                        "compiler.lowering.HOST_ONLY")
        if (cls in host_emitters) == (cls in not_emitted):
            gaps.append(f"{name}: in neither or both of numpy_host.HOST_EMITTERS and "
                        "NOT_EMITTED")
    return gaps


def test_every_built_in_op_has_every_facet():
    assert facet_gaps(OP_REGISTRY, default_registry(), HOST_ONLY, HOST_EMITTERS,
                      NOT_EMITTED) == []


class Gain(Op):
    """A fake op of a test registry: ``y = g·x``."""

    op: Literal["gain"] = "gain"
    g: float = 1.0

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        return t

    def evaluate(self, node_id: str, args: list, types: list):
        return self.g * args[0]


def test_a_new_op_without_its_tables_fails_naming_them():
    ops = {**OP_REGISTRY, "gain": Gain}
    assert facet_gaps(ops, default_registry(), HOST_ONLY, HOST_EMITTERS, NOT_EMITTED) == [
        "gain: neither or both of Gain.bound and .no_bound",
        "gain: in neither or both of the lowering registry and compiler.lowering.HOST_ONLY",
        "gain: in neither or both of numpy_host.HOST_EMITTERS and NOT_EMITTED",
    ]
    # a lowering rule (or a HOST_ONLY reason) and an emission entry close those gaps
    lowering = default_registry().copy()
    lowering.register(Gain, "decoder", lambda ctx, node, op, inputs: inputs[0], default=True)
    not_emitted = {**NOT_EMITTED, Gain: "a test op: the generated package does not know it"}
    assert facet_gaps(ops, lowering, HOST_ONLY, HOST_EMITTERS, not_emitted) == [
        "gain: neither or both of Gain.bound and .no_bound"]
    assert facet_gaps(ops, default_registry(), {**HOST_ONLY, Gain: "runs on the host"},
                      HOST_EMITTERS, not_emitted) == [
        "gain: neither or both of Gain.bound and .no_bound"]


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_has_a_reference_implementation_or_is_an_input(name, cls):
    assert cls in EVAL_REGISTRY or cls.arity == 0, f"{name}: no {cls.__name__}.evaluate"
    assert (cls in EVAL_REGISTRY) == cls.has_evaluate()


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_is_emitted_for_the_host_or_says_why_not(name, cls):
    assert (cls in HOST_EMITTERS) != (cls in NOT_EMITTED), (
        f"{name}: in neither or both of numpy_host.HOST_EMITTERS and NOT_EMITTED")
    assert cls not in NOT_EMITTED or len(NOT_EMITTED[cls]) > 20


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_has_a_bound_rule_or_says_why_not(name, cls):
    assert cls.has_bound() != bool(cls.no_bound), (
        f"{name}: neither or both of {cls.__name__}.bound and {cls.__name__}.no_bound")
    assert not cls.no_bound or len(cls.no_bound) > 20


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_weights_exist_exactly_for_the_linear_ops(name, cls):
    if cls is DFT:
        op = DFT(axis="s")
    elif cls is Linear:
        op = Linear(axis="s", matrix=[[1.0, 0.0]])
    elif cls is Window:
        op = Window(axis="s", kind="hann")
    else:
        with pytest.raises(CompileError):
            op_weights(cls.model_construct(), 2, node="n")
        return
    assert op_weights(op, 2, node="n").shape[1] == 2


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_lowers_to_spikes_or_says_why_it_runs_on_the_host(name, cls):
    registry = default_registry()
    assert registry.lowers(cls) != (cls in HOST_ONLY), (
        f"{name}: in neither or both of the lowering registry and compiler.lowering.HOST_ONLY")
    assert cls not in HOST_ONLY or len(HOST_ONLY[cls]) > 20
    spiking = [m for m in registry.motifs(cls) if m != HOST]
    if name in ("dft", "magnitude", "cfar", "classifier"):  # the papers' spiking stages
        assert spiking, f"{name}: computes on the chip in the papers, but has no spiking motif"
