r"""The ``classifier`` op: a spiking classifier of region-of-interest (ROI) sequences.

The op holds the layer stack of Vogginger et al.'s radar object classifier
(000_… §4.2): spiking convolutions, a recurrent LIF layer and a non-spiking
integrator readout, run over a sequence of RD-map ROIs with **one time step
per frame**. Weights live in an ``.npz`` file named by ``weights`` (never
opened here; :func:`Classifier.weight_shapes` says which keys and shapes the
file must hold, :func:`Classifier.check_weights` checks them).

Dynamics (every spiking layer, per step ``t``; ``I`` = the layer's input current,
the same update as :class:`compiler.snn.NeuronParams`):

.. math::

    u[t] &= (1 - d_u)\,u[t-1] + I[t] \\
    v[t] &= (1 - d_v)\,v[t-1] + u[t] \\
    s[t] &= [v[t] \ge v_{th}], \quad v[t] \leftarrow v[t] - v_{th} s[t]
            \ \text{(subtract)}\ \text{or}\ v_{reset}\ \text{(value)}

with ``u[-1] = v[-1] = 0``. Input current of each layer kind: ``conv2d``
:math:`I = W \star x` (cross-correlation, no bias); ``dense``
:math:`I = W x`; ``recurrent`` :math:`I[t] = W x[t] + R\,s[t-1]`;
``integrator`` :math:`I = W x` into a neuron that never spikes — the class
scores are its membranes ``v`` after the last frame. ``pool`` has no neurons:
``max`` takes the window's maximum (on spikes: OR), ``avg`` its mean.

Input encoding: ``levels`` turns frame ``t`` into ``len(levels)`` binary channels
``x_k[t] = [roi[t] > levels[k]]`` (spikes from comparing RD values to reference
levels); ``real`` feeds ``scale · roi[t]`` into the first layer as one real
channel (a real-valued first layer).

Examples
--------
>>> clf = Classifier(num_classes=3, weights="clf.npz",
...     encoding=LevelsEncoding(levels=(2.0,)),
...     layers=(Conv2d(channels=4, kernel=(3, 3), stride=(2, 2)), Pool(mode="max", size=(2, 2)),
...             Recurrent(units=8), Integrator(units=3)))
>>> t = TensorType(axes={"frame": 8, "range": 16, "doppler": 16})
>>> clf.infer("cls", [t]).axes
{'class': 3}
>>> clf.feature_shapes("cls", (16, 16))
[(1, 16, 16), (4, 7, 7), (4, 3, 3), (8,), (3,)]
>>> shapes = clf.weight_shapes("cls", (16, 16))
>>> list(shapes), shapes["layers.2.weight"]
(['layers.0.weight', 'layers.2.weight', 'layers.2.recurrent', 'layers.3.weight'], (8, 36))
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, FiniteFloat, PositiveInt, model_serializer, model_validator

from ir.model import IRModel, Name
from ir.ops.base import Op
from ir.types import TensorType

__all__ = [
    "LIF",
    "Classifier",
    "Conv2d",
    "Dense",
    "Encoding",
    "Integrator",
    "Layer",
    "LevelsEncoding",
    "Pool",
    "RealEncoding",
    "Recurrent",
]

Pair = tuple[PositiveInt, PositiveInt]


class _Tagged(IRModel):
    """A union member whose ``kind`` tag is always written (even when dumping non-defaults)."""

    @model_serializer(mode="wrap")
    def _keep_kind(self, handler):  # noqa: ANN001, ANN202 - pydantic's serializer protocol
        data = handler(self)
        return {"kind": self.kind, **data} if isinstance(data, dict) else data


class LIF(IRModel):
    """Neuron parameters of a spiking layer (mapped 1:1 onto ``compiler.snn.NeuronParams``).

    Parameters
    ----------
    du, dv : float
        Current and voltage decay per step in ``[0, 1]`` (``du = 1``: no synaptic memory;
        ``dv = 0``: no leak).
    v_th : float
        Threshold (> 0).
    reset : {"subtract", "value"}
        After a spike ``v -= v_th`` or ``v = v_reset``.
    v_reset : float
        The ``value`` reset's membrane.
    """

    du: float = Field(default=1.0, ge=0.0, le=1.0)
    dv: float = Field(default=0.0, ge=0.0, le=1.0)
    v_th: FiniteFloat = Field(default=1.0, gt=0.0)
    reset: Literal["subtract", "value"] = "subtract"
    v_reset: FiniteFloat = 0.0


class LevelsEncoding(_Tagged):
    """Binary input channels ``[x > level]``, one per reference level (increasing)."""

    kind: Literal["levels"] = "levels"
    levels: tuple[FiniteFloat, ...] = Field(min_length=1)

    @model_validator(mode="after")
    def _increasing(self) -> LevelsEncoding:
        if any(b <= a for a, b in zip(self.levels, self.levels[1:], strict=False)):
            raise ValueError(f"levels must increase strictly, got {list(self.levels)}")
        return self

    @property
    def channels(self) -> int:
        """Input channels of the first layer."""
        return len(self.levels)


class RealEncoding(_Tagged):
    """One real input channel ``scale · x`` (a real-valued first layer)."""

    kind: Literal["real"] = "real"
    scale: FiniteFloat = Field(default=1.0, gt=0.0)

    @property
    def channels(self) -> int:
        """Input channels of the first layer."""
        return 1


Encoding = Annotated[LevelsEncoding | RealEncoding, Field(discriminator="kind")]


class Conv2d(_Tagged):
    """Spiking 2-D convolution over the map axes; weight ``(channels, in, kh, kw)``."""

    kind: Literal["conv2d"] = "conv2d"
    channels: PositiveInt
    kernel: Pair
    stride: Pair = (1, 1)
    padding: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]] = (0, 0)
    neuron: LIF = LIF()


class Pool(_Tagged):
    """Non-overlapping pooling (stride = size, floor), no weights: ``max`` or ``avg``."""

    kind: Literal["pool"] = "pool"
    mode: Literal["max", "avg"]
    size: Pair


class Dense(_Tagged):
    """Spiking fully connected layer; weight ``(units, in)`` over the flattened input."""

    kind: Literal["dense"] = "dense"
    units: PositiveInt
    neuron: LIF = LIF()


class Recurrent(_Tagged):
    """Recurrent LIF layer; weights ``(units, in)`` and ``recurrent (units, units)``."""

    kind: Literal["recurrent"] = "recurrent"
    units: PositiveInt
    neuron: LIF = LIF()


class Integrator(_Tagged):
    """Non-spiking readout (the last layer): membranes after the last frame are the scores."""

    kind: Literal["integrator"] = "integrator"
    units: PositiveInt
    du: float = Field(default=1.0, ge=0.0, le=1.0)
    dv: float = Field(default=0.0, ge=0.0, le=1.0)


Layer = Annotated[Conv2d | Pool | Dense | Recurrent | Integrator, Field(discriminator="kind")]

_MAP_KINDS = ("conv2d", "pool")


class Classifier(Op):
    r"""Class scores of each ROI sequence: :math:`y = f_\theta(x) \in \mathbb{R}^{C}`.

    Parameters
    ----------
    num_classes : int
        Number of classes :math:`C` (>= 2); the integrator's ``units``.
    weights : str
        Path of the ``.npz`` with the trained weights (relative paths resolve against
        the current directory); keys ``layers.<i>.weight`` and ``layers.<i>.recurrent``
        as :meth:`weight_shapes` lists.
    layers : tuple of layers
        The stack (see the module docstring); empty = an opaque classifier that
        type-checks but cannot be evaluated or lowered.
    encoding : LevelsEncoding or RealEncoding
        How ROI values enter the first layer.
    time_axis : str
        The input axis of the frame sequence (one step per frame).
    map_axes : pair of str
        The two input axes the convolutions run over, in kernel order.

    Notes
    -----
    Input: real (``amplitude``, ``power`` or ``db``). With ``layers``: axes
    ``time_axis`` and ``map_axes``; any other axes (e.g. ``object``) are batch axes,
    classified independently; output = the batch axes then ``{"class": C}``.
    Without ``layers``: at least 2 axes, output ``{"class": C}``.

    Examples
    --------
    >>> t = TensorType(axes={"range": 32, "doppler": 16})
    >>> Classifier(num_classes=4, weights="clf.npz").infer("cls", [t]).axes
    {'class': 4}
    """

    no_bound: ClassVar[str] = ("scores of a trained network: bounded by its calibration, not by "
                               "its input")
    op: Literal["classifier"] = "classifier"
    num_classes: int = Field(ge=2)
    weights: str = Field(min_length=1)
    layers: tuple[Layer, ...] = ()
    encoding: Encoding = RealEncoding()
    time_axis: Name = "frame"
    map_axes: tuple[Name, Name] = ("range", "doppler")

    # ------------------------------------------------------------------ types
    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.check_value(node_id, t, ("amplitude", "power", "db"), allow_complex=False)
        if not self.layers:
            if t.ndim < 2:
                raise self.fail(
                    node_id, f"needs an input with at least 2 axes (a map); got axes {t.names}"
               )
            return TensorType(axes={"class": self.num_classes})
        wanted = (self.time_axis, *self.map_axes)
        if len(set(wanted)) != 3:
            raise self.fail(node_id, f"time_axis and map_axes must be 3 distinct axes, got "
                                     f"{list(wanted)}")
        missing = [a for a in wanted if a not in t.axes]
        if missing:
            raise self.fail(node_id, f"input axes {t.names} lack {missing} (time_axis "
                                     f"{self.time_axis!r}, map_axes {list(self.map_axes)}); "
                                     "rename the axes or set time_axis/map_axes")
        self.feature_shapes(node_id, tuple(t.axes[a] for a in self.map_axes))
        batch = {a: n for a, n in t.axes.items() if a not in wanted}
        if "class" in batch:
            raise self.fail(node_id, "a batch axis is named 'class', the output axis; rename it")
        return TensorType(axes={**batch, "class": self.num_classes})

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        """The numpy forward pass, :func:`ir.classifier_forward.evaluate_classifier`."""
        # a cycle by construction: the forward pass reads this module's layer classes
        from ir.classifier_forward.forward import evaluate_classifier
        return evaluate_classifier(node_id, self, args, types)

    def batch_axes(self, t: TensorType) -> tuple[str, ...]:
        """Input axes other than the time and map axes, in input order."""
        return tuple(a for a in t.names if a not in (self.time_axis, *self.map_axes))

    def feature_shapes(self, node_id: str, map_shape: tuple[int, int]) -> list[tuple[int, ...]]:
        """Shape after the encoding and after each layer: ``(C, H, W)`` maps, then ``(n,)``.

        Raises
        ------
        IRError
            Naming the node and layer: no layers, a map layer after a flat one, a map
            shrinking below 1, a missing or misplaced integrator, or its ``units`` not
            ``num_classes``.
        """
        if not self.layers:
            raise self.fail(node_id, "has no layers (an opaque classifier); declare 'layers'")
        shape: tuple[int, ...] = (self.encoding.channels, *map_shape)
        out = [shape]
        last = len(self.layers) - 1
        for i, layer in enumerate(self.layers):
            where = f"layer {i} ({layer.kind})"
            if (layer.kind == "integrator") != (i == last):
                raise self.fail(node_id, f"{where}: the integrator readout must be the last "
                                         "layer, and only the last")
            if layer.kind in _MAP_KINDS:
                if len(shape) != 3:
                    raise self.fail(node_id, f"{where}: a map layer after a flat layer; put "
                                             "conv2d/pool layers first")
                shape = self._map_out(node_id, where, layer, shape)
            else:
                shape = (layer.units,)
            out.append(shape)
        if self.layers[-1].units != self.num_classes:
            raise self.fail(node_id, f"layer {last} (integrator): units = "
                                     f"{self.layers[-1].units} but num_classes = "
                                     f"{self.num_classes}; make them equal")
        return out

    def _map_out(self, node_id: str, where: str, layer: Conv2d | Pool,
                 shape: tuple[int, ...]) -> tuple[int, int, int]:
        c, h, w = shape
        if layer.kind == "conv2d":
            sizes = [(n + 2 * p - k) // s + 1 for n, p, k, s in
                     zip((h, w), layer.padding, layer.kernel, layer.stride, strict=True)]
            c = layer.channels
        else:
            sizes = [n // k for n, k in zip((h, w), layer.size, strict=True)]
        if min(sizes) < 1:
            raise self.fail(node_id, f"{where}: maps an input of {h} x {w} to {sizes[0]} x "
                                     f"{sizes[1]}; need at least 1 x 1 (a smaller kernel, "
                                     "stride or pool, or a larger ROI)")
        return (c, sizes[0], sizes[1])

    def weight_shapes(self, node_id: str, map_shape: tuple[int, int]) -> dict[str, tuple]:
        """The npz keys and array shapes the weights file must hold, in layer order."""
        shapes = self.feature_shapes(node_id, map_shape)
        keys: dict[str, tuple] = {}
        for i, layer in enumerate(self.layers):
            n_in = int(np.prod(shapes[i]))
            if layer.kind == "conv2d":
                keys[f"layers.{i}.weight"] = (layer.channels, shapes[i][0], *layer.kernel)
            elif layer.kind != "pool":
                keys[f"layers.{i}.weight"] = (layer.units, n_in)
            if layer.kind == "recurrent":
                keys[f"layers.{i}.recurrent"] = (layer.units, layer.units)
        return keys

    def check_weights(self, node_id: str, map_shape: tuple[int, int],
                      arrays: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Check a weights mapping against :meth:`weight_shapes`; return float64 copies.

        Raises
        ------
        IRError
            Naming the node, the file and the key: missing or unexpected keys, a wrong
            shape, non-numeric or non-finite values.

        Examples
        --------
        >>> clf = Classifier(num_classes=2, weights="w.npz", time_axis="t",
        ...                  layers=(Integrator(units=2),))
        >>> clf.check_weights("k", (2, 2), {"layers.0.weight": np.zeros((2, 3))})
        Traceback (most recent call last):
        ...
        ir.errors.IRError: node 'k' (classifier): weights 'w.npz' key 'layers.0.weight' \
(layer 0, integrator) has shape (2, 3), expected (2, 4)
        """
        want = self.weight_shapes(node_id, map_shape)
        missing = [k for k in want if k not in arrays]
        extra = [k for k in arrays if k not in want]
        if missing or extra:
            raise self.fail(node_id, f"weights {self.weights!r}: missing keys {missing}, "
                                     f"unexpected keys {extra}; expected {list(want)}")
        out = {}
        for key, shape in want.items():
            arr = np.asarray(arrays[key])
            i = int(key.split(".")[1])
            where = f"weights {self.weights!r} key {key!r} (layer {i}, {self.layers[i].kind})"
            if arr.shape != shape:
                raise self.fail(node_id, f"{where} has shape {arr.shape}, expected {shape}")
            if arr.dtype.kind not in "iuf" or not np.all(np.isfinite(arr)):
                raise self.fail(node_id, f"{where} must hold finite real numbers (dtype "
                                         f"{arr.dtype})")
            out[key] = arr.astype(np.float64)
        return out

