"""The ``classifier`` op: a placeholder for a trained classifier on radar maps."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from pydantic import Field

from ir.ops.base import Op
from ir.types import TensorType

__all__ = ["Classifier"]


class Classifier(Op):
    r"""Class scores of a map: :math:`y = f_\theta(x) \in \mathbb{R}^{C}`.

    A placeholder: the layers of :math:`f_\theta` come with a later issue. The op
    type-checks and round-trips through chain files, but :func:`ir.evaluate.evaluate`
    raises :class:`~ir.errors.IRError` ("classifier evaluation is not implemented yet").

    Parameters
    ----------
    num_classes : int
        Number of classes :math:`C` (>= 2).
    weights : str
        Path of the trained weights, opaque to the IR (never opened here).

    Notes
    -----
    Input: real, at least 2 axes, not a mask. Output: ``{"class": num_classes}``,
    real ``amplitude`` (scores).

    Examples
    --------
    >>> t = TensorType(axes={"range": 32, "doppler": 16})
    >>> Classifier(num_classes=4, weights="clf.npz").infer("cls", [t]).axes
    {'class': 4}
    """

    op: Literal["classifier"] = "classifier"
    num_classes: int = Field(ge=2)
    weights: str = Field(min_length=1)

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude", "power", "db"), allow_complex=False)
        if t.ndim < 2:
            raise self.fail(
                node_id, f"needs an input with at least 2 axes (a map); got axes {t.names}"
            )
        return TensorType(axes={"class": self.num_classes})
