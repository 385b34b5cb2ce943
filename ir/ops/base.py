"""The base class of every op: arity, the op name, its meaning, and helpers for type checks.

An op is a frozen record of parameters with a literal ``op`` field (its name in
chain files) and a pure :meth:`Op.infer` that maps input types to the output
type, raising :class:`~ir.errors.IRError` that names the node, the op and what
is wrong.  The op class is also the one home of the op's meaning: its reference
implementation (:meth:`Op.evaluate`, the golden numpy semantics
:func:`ir.interpreter.evaluate` runs) and its calibration bound (:meth:`Op.bound`,
or :attr:`Op.no_bound` saying why it has none).  The tables other layers read
(``ir.EVAL_REGISTRY``, the bound rules, the exported names) are derived from the
op registry (:mod:`ir.ops.registry`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from ir.errors import IRError
from ir.model import IRModel
from ir.types import TensorType

__all__ = ["Op"]


class Op(IRModel):
    """Base of all ops.

    Class attributes
    ----------------
    arity : int
        Number of inputs the op takes (0 for graph inputs).
    is_output : bool
        Whether the op marks a graph output.
    no_bound : str
        Why the op has no calibration bound (empty when :meth:`bound` gives one).
    """

    arity: ClassVar[int] = 1
    is_output: ClassVar[bool] = False
    no_bound: ClassVar[str] = ""

    op: str

    @classmethod
    def op_name(cls) -> str:
        """The op's name in chain files (the default of its ``op`` field)."""
        return cls.model_fields["op"].default

    @classmethod
    def describe_kind(cls) -> str:
        return f"op {cls.op_name()!r}"

    def params(self) -> dict[str, Any]:
        """Parameters that differ from their defaults, as JSON-compatible values.

        Examples
        --------
        >>> from ir.ops.linear import Window
        >>> Window(axis="sample").params()
        {'axis': 'sample'}
        """
        dumped = self.model_dump(mode="json", exclude_defaults=True)
        dumped.pop("op", None)
        return dumped

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        """The output type of this op applied to ``inputs`` (overridden by each op)."""
        raise NotImplementedError(f"{type(self).__name__}.infer")

    # -- the op's meaning (overridden by each op that has it) ---------------------------

    def evaluate(self, node_id: str, args: list[np.ndarray],
                 types: list[TensorType]) -> np.ndarray:
        """The reference implementation: the node's value from its input values.

        Parameters
        ----------
        node_id : str
            The node (named in errors).
        args : list of ndarray
            The input values, in input order, axes in the order of their types.
        types : list of TensorType
            Their types.

        Returns
        -------
        ndarray
            The value, shaped and typed as :meth:`infer` says (the interpreter checks it).

        Examples
        --------
        >>> import numpy as np
        >>> from ir.ops.linear import Sum
        >>> t = TensorType(axes={"rx": 2, "range": 3})
        >>> Sum(axis="rx").evaluate("s", [np.arange(6.0).reshape(2, 3)], [t]).tolist()
        [3.0, 5.0, 7.0]
        """
        raise NotImplementedError(f"{type(self).__name__}.evaluate")

    def bound(self, node_id: str, bounds: list[float], types: list[TensorType]) -> float:
        """The calibration bound: the largest ``|Re|``/``|Im|`` of the value, worst case.

        Parameters
        ----------
        node_id : str
            The node (named in errors).
        bounds : list of float
            The bounds of the input values, in input order.
        types : list of TensorType
            Their types.

        Returns
        -------
        float

        Examples
        --------
        >>> from ir.ops.elementwise import Add
        >>> Add().bound("s", [1.0, 2.5], [])
        3.5
        """
        raise NotImplementedError(f"{type(self).__name__}.bound")

    def linear_map(self, n_in: int) -> np.ndarray | None:
        """The complex matrix ``W`` (``n_out x n_in``) of a linear op along its axis, else None.

        Examples
        --------
        >>> from ir.ops.elementwise import Magnitude
        >>> Magnitude().linear_map(4) is None
        True
        """
        return None

    @classmethod
    def has_evaluate(cls) -> bool:
        """Whether the class defines (or inherits) a reference implementation.

        Examples
        --------
        >>> from ir.ops.io import Input, Output
        >>> Output.has_evaluate(), Input.has_evaluate()
        (True, False)
        """
        return cls.evaluate is not Op.evaluate

    @classmethod
    def has_bound(cls) -> bool:
        """Whether the class defines (or inherits) a calibration bound rule.

        Examples
        --------
        >>> from ir.ops.elementwise import Add, Log
        >>> Add.has_bound(), Log.has_bound(), Log.no_bound[:16]
        (True, False, 'no useful worst ')
        """
        return cls.bound is not Op.bound

    # -- helpers for infer -------------------------------------------------------------

    def fail(self, node_id: str, message: str) -> IRError:
        """An :class:`IRError` reading ``node '<id>' (<op>): <message>``."""
        return IRError(f"node {node_id!r} ({self.op}): {message}", node=node_id)

    def expect_inputs(self, node_id: str, inputs: Sequence[TensorType]) -> list[TensorType]:
        """Check the number of inputs against :attr:`arity` and return them as a list."""
        if len(inputs) != self.arity:
            plural = "input" if self.arity == 1 else "inputs"
            raise self.fail(
                node_id,
                f"takes {self.arity} {plural}, got {len(inputs)}; "
                + ("remove 'input'/'inputs'" if self.arity == 0 else "fix 'input'/'inputs'"),
            )
        return list(inputs)

    def axis_index(self, node_id: str, t: TensorType, axis: str, field: str = "axis") -> int:
        """Dimension index of ``axis`` in ``t``; unknown axes name the available ones."""
        if axis not in t.axes:
            raise self.fail(
                node_id, f"{field} {axis!r} is not an axis of the input; available axes: {t.names}"
            )
        return t.names.index(axis)

    def check_new_axis(self, node_id: str, t: TensorType, old: str, new: str, field: str) -> None:
        """Reject renaming ``old`` to ``new`` when ``new`` is another axis of ``t``."""
        if new != old and new in t.axes:
            raise self.fail(
                node_id,
                f"{field} {new!r} duplicates an existing axis name (input axes {t.names}); "
                "pick a new name",
            )

    def check_value(
        self, node_id: str, t: TensorType, domains: Sequence[str], *, allow_complex: bool
    ) -> None:
        """Reject complex inputs (unless allowed) and inputs whose domain is not in ``domains``."""
        if t.complex and not allow_complex:
            raise self.fail(
                node_id,
                f"input is complex; {self.op} takes real values (add a magnitude node before it)",
            )
        if t.domain not in domains:
            raise self.fail(
                node_id,
                f"input domain {t.domain!r} is not accepted; {self.op} takes {list(domains)}",
            )
