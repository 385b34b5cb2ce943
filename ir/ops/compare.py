"""Detection ops that compare values and output masks: ``cfar`` and ``threshold``.

``cfar``'s reference implementation is :func:`radar.cfar.cfar`.  A mask has no
calibration bound (:attr:`~ir.ops.base.Op.no_bound`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, FiniteFloat, NonNegativeInt, PositiveInt, model_validator

from ir.model import Name
from ir.ops.base import Op
from ir.types import TensorType
from radar import cfar_theory
from radar.cfar import cfar

__all__ = ["CFAR", "CfarWindow", "EdgeMode", "Threshold"]

EdgeMode = Literal["wrap", "clip"]


@dataclass(frozen=True)
class CfarWindow:
    """A CFAR window resolved against an input type: one entry per CFAR axis.

    Attributes
    ----------
    axes : tuple of str
        The CFAR axes, in the order given (default: all input axes).
    guard, train : tuple of int
        Guard and training cells per side, per axis.
    edge : tuple of {"wrap", "clip"}
        Edge handling per axis.
    """

    axes: tuple[str, ...]
    guard: tuple[int, ...]
    train: tuple[int, ...]
    edge: tuple[str, ...]

    @property
    def sizes(self) -> tuple[int, ...]:
        """Window extent per axis, :math:`2(g + t) + 1`."""
        return tuple(2 * (g + t) + 1 for g, t in zip(self.guard, self.train, strict=True))

    @property
    def n_train(self) -> int:
        r"""Training cells of an interior cell, :math:`\prod(2(g+t)+1) - \prod(2g+1)`.

        Examples
        --------
        >>> CfarWindow(("range", "doppler"), (3, 3), (4, 4), ("clip", "wrap")).n_train
        176
        """
        return math.prod(self.sizes) - math.prod(2 * g + 1 for g in self.guard)


class CFAR(Op):
    r"""Constant-false-alarm-rate detection over a rectangular window.

    For each cell under test (CUT) :math:`x_0`, the training cells are the cells
    of the window :math:`\prod_a [-(g_a+t_a), g_a+t_a]` outside the guard block
    :math:`\prod_a [-g_a, g_a]` (which holds the CUT). With :math:`N` training
    values :math:`x_1 \dots x_N`:

    .. math:: \mathrm{det} = x_0 > \alpha\, P, \qquad
              P = \begin{cases} \frac{1}{N}\sum_i x_i & \text{ca} \\
                                x_{(k)} \text{, the } k\text{-th largest (1-indexed)} & \text{os}
                  \end{cases}

    For an interior cell :math:`N = \prod_a (2(g_a+t_a)+1) - \prod_a (2g_a+1)`.
    Near an edge, ``wrap`` reads cells periodically; ``clip`` uses only the
    training cells inside the map (:func:`radar.cfar.cfar` defines the details).

    Parameters
    ----------
    kind : {"ca", "os"}
        Cell averaging or ordered statistic.
    axes : list of str, optional
        The axes the window spans (default: every input axis, in order). Other
        axes are a batch: each slice is processed independently.
    guard, train : int or list of int
        Guard and training cells **per side**; an int applies to every axis,
        a list gives one value per entry of ``axes``. ``train`` may be 0 on an
        axis, but :math:`N \ge 1`.
    alpha : float, optional
        Threshold factor :math:`\alpha > 0`.
    pfa : float, optional
        Design false-alarm probability in (0, 1); :math:`\alpha` then comes from
        :func:`radar.cfar_theory.ca_alpha` / :func:`~radar.cfar_theory.os_alpha`
        for the interior :math:`N`. That theory assumes square-law detection
        (i.i.d. exponential noise), so ``pfa`` needs a ``power`` input.
        Give exactly one of ``alpha`` and ``pfa``.
    k : int, optional
        Rank for ``os`` (required there, 1..N); forbidden for ``ca``.
    edge : {"wrap", "clip"} or list of them, default "clip"
        Edge handling, one for every axis or one per entry of ``axes``.

    Notes
    -----
    Input: real ``amplitude``, ``power`` or ``db``. Output: ``mask``, same axes.

    Examples
    --------
    >>> t = TensorType(axes={"range": 256, "doppler": 64})
    >>> det = CFAR(kind="os", guard=3, train=4, k=132, alpha=1.2, edge=["clip", "wrap"])
    >>> det.infer("det", [t]).domain
    'mask'
    >>> det.window("det", t).n_train
    176
    """

    no_bound: ClassVar[str] = "a comparison: a mask, not a value range"
    op: Literal["cfar"] = "cfar"
    kind: Literal["ca", "os"]
    axes: tuple[Name, ...] | None = Field(default=None, min_length=1)
    guard: NonNegativeInt | tuple[NonNegativeInt, ...]
    train: NonNegativeInt | tuple[NonNegativeInt, ...]
    alpha: FiniteFloat | None = Field(default=None, gt=0)
    pfa: float | None = Field(default=None, gt=0, lt=1)
    k: PositiveInt | None = None
    edge: EdgeMode | tuple[EdgeMode, ...] = "clip"

    @model_validator(mode="after")
    def _consistent(self) -> CFAR:
        if (self.alpha is None) == (self.pfa is None):
            raise ValueError("give exactly one of 'alpha' and 'pfa'")
        if self.kind == "os" and self.k is None:
            raise ValueError("kind 'os' needs the rank 'k' (k-th largest training cell)")
        if self.kind == "ca" and self.k is not None:
            raise ValueError("'k' is only for kind 'os'; remove it for 'ca'")
        for field in ("guard", "train", "edge"):
            value = getattr(self, field)
            if isinstance(value, tuple) and not value:
                raise ValueError(f"{field!r} must not be an empty list")
        return self

    def window(self, node_id: str, t: TensorType) -> CfarWindow:
        """Resolve ``axes``, ``guard``, ``train`` and ``edge`` against input type ``t``.

        Raises
        ------
        IRError
            Unknown or repeated axes, per-axis lists of the wrong length, a window
            larger than the map, no training cells, or ``k`` outside 1..N.
        """
        axes = self.axes if self.axes is not None else t.names
        if len(set(axes)) != len(axes):
            raise self.fail(node_id, f"axes {list(axes)} repeat an axis name; list each once")
        for axis in axes:
            self.axis_index(node_id, t, axis, field="axes entry")
        guard = self._per_axis(node_id, "guard", self.guard, axes)
        train = self._per_axis(node_id, "train", self.train, axes)
        edge = self._per_axis(node_id, "edge", self.edge, axes)
        win = CfarWindow(tuple(axes), guard, train, edge)
        for axis, extent, g, tr in zip(axes, win.sizes, guard, train, strict=True):
            if extent > t.axes[axis]:
                raise self.fail(
                    node_id,
                    f"window 2*(guard+train)+1 = 2*({g}+{tr})+1 = {extent} is larger than "
                    f"axis {axis!r} of size {t.axes[axis]}; reduce guard/train on that axis",
                )
        if win.n_train < 1:
            raise self.fail(node_id, f"no training cells (train={list(train)}); use train >= 1")
        if self.k is not None and not 1 <= self.k <= win.n_train:
            raise self.fail(
                node_id,
                f"k={self.k} is outside 1..{win.n_train} (N_train for guard {list(guard)}, "
                f"train {list(train)}); choose k in 1..{win.n_train}",
            )
        return win

    def _per_axis(self, node_id: str, field: str, value: object, axes: Sequence[str]) -> tuple:
        if not isinstance(value, tuple):
            return (value,) * len(axes)
        if len(value) != len(axes):
            raise self.fail(
                node_id,
                f"{field} has {len(value)} entries but the CFAR spans {len(axes)} axes "
                f"{list(axes)}; give one entry per axis or a single value",
            )
        return value

    def alpha_for(self, n_train: int) -> float:
        """The threshold factor: ``alpha``, or the one that yields ``pfa`` for ``n_train`` cells.

        Examples
        --------
        >>> CFAR(kind="ca", guard=1, train=2, alpha=3.0).alpha_for(8)
        3.0
        """
        if self.alpha is not None:
            return self.alpha
        if self.kind == "ca":
            return float(cfar_theory.ca_alpha(self.pfa, n_train))
        return float(cfar_theory.os_alpha(self.pfa, n_train, self.k))

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude", "power", "db"), allow_complex=False)
        if self.pfa is not None and t.domain != "power":
            raise self.fail(
                node_id,
                f"pfa assumes square-law (power) input but the input domain is {t.domain!r}; "
                "use magnitude kind 'square' before the CFAR, or give alpha instead of pfa",
            )
        self.window(node_id, t)
        return t.replace(domain="mask")

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        win = self.window(node_id, types[0])
        src = [types[0].index(a) for a in win.axes]
        dst = list(range(-len(src), 0))
        moved = np.moveaxis(args[0], src, dst)
        det = cfar(
            moved,
            kind=self.kind,
            guard=list(win.guard),
            train=list(win.train),
            alpha=self.alpha_for(win.n_train),
            k=self.k,
            edge=list(win.edge),
        )
        return np.moveaxis(det, dst, src)


class Threshold(Op):
    r"""Fixed threshold: :math:`y = x > v` (``strict``) or :math:`y = x \ge v`.

    Parameters
    ----------
    value : float
        The threshold :math:`v`, in the input's units.
    strict : bool, default True
        Strict (``>``) or not (``>=``) comparison.

    Notes
    -----
    Input: real ``amplitude``, ``power`` or ``db``. Output: ``mask``, same axes.

    Examples
    --------
    >>> t = TensorType(axes={"range": 8}, domain="db")
    >>> Threshold(value=-20.0).infer("thr", [t]).domain
    'mask'
    """

    no_bound: ClassVar[str] = "a comparison: a mask, not a value range"
    op: Literal["threshold"] = "threshold"
    value: FiniteFloat
    strict: bool = True

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude", "power", "db"), allow_complex=False)
        return t.replace(domain="mask")

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return args[0] > self.value if self.strict else args[0] >= self.value
