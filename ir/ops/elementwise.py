"""Elementwise ops: ``magnitude``, ``log`` (decibels) and ``add``.

Their reference implementations delegate to :mod:`radar.dsp`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import ClassVar, Literal

import numpy as np
from pydantic import FiniteFloat

from ir.ops.base import Op
from ir.types import TensorType
from radar.dsp import magnitude, to_db

__all__ = ["Add", "Log", "Magnitude", "MagnitudeKind"]

MagnitudeKind = Literal["l2", "l1", "square"]


class Magnitude(Op):
    r"""Magnitude of each (complex or real) amplitude :math:`x = a + ib`.

    ===========  ==============================  ===============
    kind         :math:`y`                       output domain
    ===========  ==============================  ===============
    ``l2``       :math:`\sqrt{a^2 + b^2}`        amplitude
    ``l1``       :math:`|a| + |b|`               amplitude
    ``square``   :math:`a^2 + b^2`               power
    ===========  ==============================  ===============

    Parameters
    ----------
    kind : {"l2", "l1", "square"}, default "l2"

    Notes
    -----
    Input: ``amplitude``, real or complex. Output: real, same axes.

    Examples
    --------
    >>> t = TensorType(axes={"range": 8}, complex=True)
    >>> Magnitude(kind="square").infer("pow", [t])
    TensorType(axes={'range': 8}, complex=False, domain='power')
    """

    op: Literal["magnitude"] = "magnitude"
    kind: MagnitudeKind = "l2"

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude",), allow_complex=True)
        domain = "power" if self.kind == "square" else "amplitude"
        return t.replace(complex=False, domain=domain)

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return magnitude(args[0], self.kind)

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """``l2``: √n·b, ``l1``: n·b, ``square``: n·b² (n = 2 parts for a complex input, else 1)."""
        n = 2 if types[0].complex else 1
        b = bounds[0]
        return {"l2": math.sqrt(n) * b, "l1": n * b, "square": n * b * b}[self.kind]


class Log(Op):
    r"""Level in decibels, floored: amplitude :math:`y = \max(20\log_{10}|x|, f)`,
    power :math:`y = \max(10\log_{10} x, f)` with :math:`f` = ``floor_db``.

    Parameters
    ----------
    floor_db : float, default -300.0
        Lowest output level; zeros (and values below it) map to ``floor_db``.

    Notes
    -----
    Input: real ``amplitude`` or ``power`` (the domain picks 20 or 10 log10).
    Output: ``db``, same axes. Complex input is rejected (take a magnitude first).

    Examples
    --------
    >>> t = TensorType(axes={"range": 8}, domain="power")
    >>> Log().infer("db", [t]).domain
    'db'
    """

    no_bound: ClassVar[str] = "no useful worst case (log of a value near 0 is unbounded below)"
    op: Literal["log"] = "log"
    floor_db: FiniteFloat = -300.0

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude", "power"), allow_complex=False)
        return t.replace(domain="db")

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return to_db(args[0], domain=types[0].domain, floor_db=self.floor_db)


class Add(Op):
    r"""Elementwise sum of two values of the same axes and domain: :math:`y = a + b`.

    Complex if either input is.  Used, e.g., to add back a part of a signal that
    was computed apart (the static part over chirps, :mod:`compiler.passes.static_split`).

    Examples
    --------
    >>> t = TensorType(axes={"doppler": 4, "range": 8})
    >>> Add().infer("s", [t, t.replace(complex=True)]).complex
    True
    """

    arity: ClassVar[int] = 2
    op: Literal["add"] = "add"

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        a, b = self.expect_inputs(node_id, inputs)
        if a.axes != b.axes or a.domain != b.domain:
            raise self.fail(node_id, f"adds values of the same axes and domain; got {a.axes} "
                                     f"({a.domain}) and {b.axes} ({b.domain})")
        self.check_value(node_id, a, ("amplitude", "power"), allow_complex=True)
        return a.replace(complex=a.complex or b.complex)

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return args[0] + args[1]

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """The sum of the two bounds."""
        return bounds[0] + bounds[1]
