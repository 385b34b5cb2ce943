"""Every op of the IR answers for each per-op facet, or says why it has none (issue 20, item 6).

An op's meaning is spread over tables by op type: its reference implementation
(``ir.EVAL_REGISTRY``), its host emission in generated packages
(``backends.emit.numpy_host``), its calibration bound (``compiler.calibration_bounds``),
its weight matrix (``op_weights``) and its lowering rules (``default_registry``).  A new op
that forgets one of them fails here, naming the table.
"""

from __future__ import annotations

import pytest

from backends.emit.numpy_host import HOST_EMITTERS, NOT_EMITTED
from compiler.calibration_bounds import BOUND_RULES, NO_BOUND
from compiler.lowering import default_registry
from compiler.lowering.dft_common import op_weights
from compiler.lowering.registry import HOST
from ir.errors import CompileError
from ir.implementations import EVAL_REGISTRY
from ir.ops import DFT, OP_REGISTRY, Linear, Window

OPS = sorted(OP_REGISTRY.items())


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_has_a_reference_implementation_or_is_an_input(name, cls):
    assert cls in EVAL_REGISTRY or cls.arity == 0, f"{name}: no entry in ir.EVAL_REGISTRY"


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_is_emitted_for_the_host_or_says_why_not(name, cls):
    assert (cls in HOST_EMITTERS) != (cls in NOT_EMITTED), (
        f"{name}: in neither or both of numpy_host.HOST_EMITTERS and NOT_EMITTED")
    assert cls not in NOT_EMITTED or len(NOT_EMITTED[cls]) > 20


@pytest.mark.parametrize(("name", "cls"), OPS)
def test_every_op_has_a_bound_rule_or_says_why_not(name, cls):
    assert (cls in BOUND_RULES) != (cls in NO_BOUND), (
        f"{name}: in neither or both of calibration_bounds.BOUND_RULES and NO_BOUND")


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
def test_every_op_lowers_to_spikes_or_runs_on_the_host(name, cls):
    motifs = default_registry().motifs(cls)
    assert motifs, f"{name}: no lowering at all"
    spiking = [m for m in motifs if m != HOST]
    if name in ("dft", "magnitude", "cfar", "classifier"):  # the papers' spiking stages
        assert spiking, f"{name}: computes on the chip in the papers, but has no spiking motif"
