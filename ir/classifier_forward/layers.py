r"""The classifier's layer stack as sparse matrices and per-layer dynamics.

Every layer with weights becomes one matrix ``M`` of shape ``(n_in, n_out)`` over the
flattened (channel-major, ``C x H x W``) features, so a layer's input current is
``I = s_in · M`` (plus ``s[t-1] · R`` for a recurrent layer):

* ``conv2d``: :math:`M[(c_i, h, w), (c_o, y, x)] = K[c_o, c_i, h - (y s_h - p_h),
  w - (x s_w - p_w)]` where the kernel index is in range (zero padding = no synapse);
* ``dense`` / ``recurrent`` / ``integrator``: :math:`M = W^T` (and :math:`R = W_{rec}^T`);
* ``pool`` ``avg``: a matrix of ``1/(p_h p_w)`` that is **folded** into the next
  layer's matrix (:math:`M \leftarrow P M`; pooling is linear, so no neurons);
* ``pool`` ``max``: on binary spikes the maximum is an OR — one neuron per output with
  weight 1 from its window, threshold 1, no memory (``du = dv = 1``).

The float forward pass (:mod:`ir.classifier_forward.forward`) and the lowering
(:mod:`compiler.lowering.classifier`) both use these matrices and the same
:class:`LayerDynamics` (the lowering turns them into :class:`compiler.snn.NeuronParams`,
field for field), so they compute the same sums.

Examples
--------
>>> from ir.ops.classify import Classifier, Conv2d, Integrator, LevelsEncoding
>>> op = Classifier(num_classes=2, weights="w.npz", encoding=LevelsEncoding(levels=(1.0,)),
...                 layers=(Conv2d(channels=1, kernel=(2, 2)), Integrator(units=2)))
>>> w = {"layers.0.weight": np.ones((1, 1, 2, 2)), "layers.1.weight": np.ones((2, 4))}
>>> plans = build_layer_plan(op, w, (3, 3))
>>> [(p.kind, p.matrix.shape, p.matrix.nnz) for p in plans]
[('spiking', (9, 4), 16), ('integrator', (4, 2), 8)]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp

from ir.ops.classify import LIF, Classifier, Conv2d, Integrator, Pool

__all__ = ["LayerDynamics", "LayerPlan", "build_layer_plan", "conv_matrix", "layer_dynamics",
           "pool_matrix"]


@dataclass(frozen=True)
class LayerDynamics:
    r"""One layer's neuron update: :math:`u \leftarrow (1-d_u)u + I`, :math:`v \leftarrow
    (1-d_v)v + u`, a spike and reset when :math:`v \ge v_{th}` (never for a read-out).

    Attributes
    ----------
    du, dv, v_th : float
        Current and membrane decays, threshold.
    reset : {"subtract", "value"} or None
        The reset; None: the neuron model's default (``subtract``).
    v_reset : float or None
        The membrane after a ``value`` reset; None: the default (0).
    spiking : bool
        False for the integrator read-out (it never spikes).
    """

    du: float
    dv: float
    v_th: float
    reset: Literal["subtract", "value"] | None = None
    v_reset: float | None = None
    spiking: bool = True

    @property
    def reset_mode(self) -> str:
        """The reset, with the default filled in."""
        return self.reset or "subtract"

    @property
    def reset_value(self) -> float:
        """The ``value`` reset's membrane, with the default filled in."""
        return 0.0 if self.v_reset is None else self.v_reset


@dataclass(frozen=True, eq=False)
class LayerPlan:
    """One population of the classifier: its input matrix, recurrence and dynamics.

    Attributes
    ----------
    index : int
        Index of the op layer it implements (a folded avg pool has none of its own).
    kind : {"spiking", "or", "integrator"}
        Spiking LIF layer, max-pool OR layer, or the non-spiking readout.
    matrix : scipy.sparse.csr_matrix, shape (n_in, n_out)
        Input weights over the flattened previous features.
    recurrent : scipy.sparse.csr_matrix or None
        ``(n_out, n_out)`` weights of the previous step's own spikes.
    params : LayerDynamics
        The population's dynamics.
    shape : tuple of int
        Output feature shape ``(C, H, W)`` or ``(n,)``.
    """

    index: int
    kind: Literal["spiking", "or", "integrator"]
    matrix: sp.csr_matrix
    recurrent: sp.csr_matrix | None
    params: LayerDynamics
    shape: tuple[int, ...]

    @property
    def size(self) -> int:
        """Neurons in the layer."""
        return int(np.prod(self.shape))


def layer_dynamics(neuron: LIF | Integrator | None) -> LayerDynamics:
    """The :class:`LayerDynamics` of a layer (``None``: the OR neuron of a max pool).

    Examples
    --------
    >>> layer_dynamics(LIF(dv=0.25, reset="value")).reset
    'value'
    >>> layer_dynamics(Integrator(units=3)).spiking
    False
    """
    if neuron is None:
        return LayerDynamics(du=1.0, dv=1.0, v_th=1.0, reset="value")
    if isinstance(neuron, Integrator):
        return LayerDynamics(du=neuron.du, dv=neuron.dv, v_th=1.0, spiking=False)
    return LayerDynamics(du=neuron.du, dv=neuron.dv, v_th=neuron.v_th, reset=neuron.reset,
                         v_reset=neuron.v_reset)


def conv_matrix(kernel: np.ndarray, in_shape: tuple[int, int, int], stride: tuple[int, int],
                padding: tuple[int, int]) -> tuple[sp.csr_matrix, tuple[int, int, int]]:
    """The ``(C_in H W, C_out H' W')`` matrix of a zero-padded strided cross-correlation.

    Examples
    --------
    >>> m, shape = conv_matrix(np.array([[[[1.0, 2.0]]]]), (1, 1, 3), (1, 1), (0, 0))
    >>> m.toarray().tolist(), shape
    ([[1.0, 0.0], [2.0, 1.0], [0.0, 2.0]], (1, 1, 2))
    """
    c_out, c_in, kh, kw = kernel.shape
    _, h, w = in_shape
    (sh, sw), (ph, pw) = stride, padding
    oh, ow = (h + 2 * ph - kh) // sh + 1, (w + 2 * pw - kw) // sw + 1
    co, ci, a, b, y, x = np.ix_(*(np.arange(n) for n in (c_out, c_in, kh, kw, oh, ow)))
    hh, ww = y * sh - ph + a, x * sw - pw + b
    full = (c_out, c_in, kh, kw, oh, ow)
    hh, ww = np.broadcast_to(hh, full), np.broadcast_to(ww, full)
    vals = np.broadcast_to(kernel[:, :, :, :, None, None], full)
    keep = (hh >= 0) & (hh < h) & (ww >= 0) & (ww < w) & (vals != 0)
    rows = (np.broadcast_to(ci, full) * h + hh) * w + ww
    cols = (np.broadcast_to(co, full) * oh + np.broadcast_to(y, full)) * ow \
        + np.broadcast_to(x, full)
    m = sp.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(c_in * h * w,
                                                                      c_out * oh * ow))
    return m, (c_out, oh, ow)


def pool_matrix(in_shape: tuple[int, int, int], size: tuple[int, int],
                value: float) -> tuple[sp.csr_matrix, tuple[int, int, int]]:
    """The ``(C H W, C H' W')`` 0/``value`` matrix of non-overlapping pooling windows.

    Examples
    --------
    >>> m, shape = pool_matrix((1, 2, 3), (2, 2), 1.0)
    >>> m.toarray().ravel().tolist(), shape
    ([1.0, 1.0, 0.0, 1.0, 1.0, 0.0], (1, 1, 1))
    """
    c, h, w = in_shape
    oh, ow = h // size[0], w // size[1]
    ci, hh, ww = np.meshgrid(np.arange(c), np.arange(h), np.arange(w), indexing="ij")
    y, x = hh // size[0], ww // size[1]
    keep = (y < oh) & (x < ow)
    rows = ((ci * h + hh) * w + ww)[keep]
    cols = ((ci * oh + y) * ow + x)[keep]
    m = sp.csr_matrix((np.full(rows.size, value), (rows, cols)), shape=(c * h * w, c * oh * ow))
    return m, (c, oh, ow)


def build_layer_plan(op: Classifier, weights: Mapping[str, np.ndarray], map_shape: tuple[int, int],
               node_id: str = "classifier") -> list[LayerPlan]:
    """The populations of the classifier (see the module docstring).

    Parameters
    ----------
    op : Classifier
        The op (with layers).
    weights : mapping of str to ndarray
        The weights (checked with :meth:`Classifier.check_weights`).
    map_shape : (int, int)
        ROI size along ``op.map_axes``.
    node_id : str
        Named in errors.

    Returns
    -------
    list of LayerPlan

    Raises
    ------
    IRError
        For bad shapes or weights, or a ``max`` pool whose input is not binary (after an
        ``avg`` pool or on a ``real`` encoding).
    """
    arrays = op.check_weights(node_id, map_shape, weights)
    shapes = op.feature_shapes(node_id, map_shape)
    binary = op.encoding.kind == "levels"
    pending: sp.csr_matrix | None = None
    plans: list[LayerPlan] = []
    for i, layer in enumerate(op.layers):
        in_shape = shapes[i]
        if isinstance(layer, Pool):
            if layer.mode == "avg":
                m, _ = pool_matrix(in_shape, layer.size, 1.0 / (layer.size[0] * layer.size[1]))
                pending = m if pending is None else pending @ m
                binary = False
                continue
            if not binary:
                raise op.fail(node_id, f"layer {i} (pool max): needs binary spikes as input "
                                       "(after a spiking layer or a levels encoding), not after "
                                       "an avg pool or a real encoding; use mode 'avg'")
            m, _ = pool_matrix(in_shape, layer.size, 1.0)
            kind, rec, params = "or", None, layer_dynamics(None)
        elif isinstance(layer, Conv2d):
            m, _ = conv_matrix(arrays[f"layers.{i}.weight"], in_shape, layer.stride,
                               layer.padding)
            kind, rec, params = "spiking", None, layer_dynamics(layer.neuron)
        else:
            m = sp.csr_matrix(arrays[f"layers.{i}.weight"].T)
            rec = sp.csr_matrix(arrays[f"layers.{i}.recurrent"].T) \
                if layer.kind == "recurrent" else None
            is_out = isinstance(layer, Integrator)
            kind = "integrator" if is_out else "spiking"
            params = layer_dynamics(layer if is_out else layer.neuron)
        if pending is not None:
            m, pending = sp.csr_matrix(pending @ m), None
        m.eliminate_zeros()
        plans.append(LayerPlan(index=i, kind=kind, matrix=m.tocsr(), recurrent=rec,
                               params=params, shape=shapes[i + 1]))
        binary = kind != "integrator"
    return plans
