r"""The numpy forward pass of the classifier: the reference semantics of the ``classifier`` op.

One step per frame ``t``. The encoding turns frame ``t`` into the first layer's input
(``levels``: binary channels ``[x > level_k]``; ``real``: ``scale · x``); every
population of :func:`ir.classifier_forward.layers.build_layer_plan` then updates in order, in the
same step (the spiking network's zero-delay projections):

.. math::

    I[t] = s_{in}[t]\, M + s[t-1]\, R, \quad u[t] = (1-d_u)u[t-1] + I[t], \quad
    v[t] = (1-d_v)v[t-1] + u[t],

then spikes ``v >= v_th`` with reset (``subtract`` / ``value``), none for the
integrator. The scores are the integrator's ``v`` after the last frame.

Activity (per sample, summed over the frames): spikes of every population (the
input's spikes counted separately) and synaptic events — every spike times the
synapses it drives (its row's non-zeros in ``M`` and ``R``). With a ``real``
encoding the first layer does ``T · nnz(M_1)`` multiply-accumulates instead.

Examples
--------
>>> from ir.ops.classify import Classifier, Dense, Integrator, LevelsEncoding
>>> op = Classifier(num_classes=2, weights="w.npz", time_axis="t",
...                 encoding=LevelsEncoding(levels=(0.5,)),
...                 layers=(Dense(units=1), Integrator(units=2)))
>>> w = {"layers.0.weight": np.ones((1, 4)), "layers.1.weight": np.array([[1.0], [-1.0]])}
>>> x = np.array([[[[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 0.0]]]])  # 1 sample, 2 frames
>>> r = classify(op, w, x)
>>> r.scores.tolist(), r.spikes.tolist(), r.input_spikes.tolist()
([[1.0, -1.0]], [[1, 0]], [1])
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ir.classifier_forward.layers import LayerPlan, build_layer_plan
from ir.classifier_forward.weights import load_weights
from ir.errors import IRError
from ir.ops.classify import Classifier
from ir.types import TensorType

__all__ = ["ForwardResult", "classify", "encode_frames", "evaluate_classifier", "run_plan"]


@dataclass(frozen=True, eq=False)
class ForwardResult:
    """Scores and activity of a batch.

    Attributes
    ----------
    scores : ndarray, shape (n, classes)
        Integrator membranes after the last frame.
    spikes : ndarray of int, shape (n, populations)
        Spikes per population (the integrator's column is 0).
    input_spikes : ndarray of int, shape (n,)
        Input spikes (``levels`` encoding; 0 for ``real``).
    synaptic_events : ndarray of int, shape (n,)
        Spikes times their synapses, input spikes included.
    macs : int
        Multiply-accumulates of a real-valued first layer per sample (0 for ``levels``).
    """

    scores: np.ndarray
    spikes: np.ndarray
    input_spikes: np.ndarray
    synaptic_events: np.ndarray
    macs: int

    @property
    def predictions(self) -> np.ndarray:
        """``argmax`` of the scores (first maximum on ties)."""
        return np.argmax(self.scores, axis=1)


def encode_frames(op: Classifier, x: np.ndarray) -> np.ndarray:
    """``(n, T, H, W)`` ROIs -> ``(n, T, C·H·W)`` first-layer input (channel-major).

    Examples
    --------
    >>> from ir.ops.classify import LevelsEncoding
    >>> op = Classifier(num_classes=2, weights="w", encoding=LevelsEncoding(levels=(0.0, 1.0)))
    >>> encode_frames(op, np.array([[[[0.5, 2.0]]]])).tolist()
    [[[1.0, 1.0, 0.0, 1.0]]]
    """
    x = np.asarray(x, dtype=np.float64)
    n, t = x.shape[:2]
    if op.encoding.kind == "real":
        return (op.encoding.scale * x).reshape(n, t, -1)
    levels = np.asarray(op.encoding.levels)[None, None, :, None, None]
    return (x[:, :, None] > levels).astype(np.float64).reshape(n, t, -1)


def run_plan(plans: list[LayerPlan], inputs: np.ndarray, *, binary_input: bool) -> ForwardResult:
    """Run the populations over ``inputs`` of shape ``(n, T, n_in)`` (see the module docstring).

    Raises
    ------
    ValueError
        If the input width does not match the first matrix.
    """
    n, steps, width = inputs.shape
    if width != plans[0].matrix.shape[0]:
        raise ValueError(f"inputs have {width} features, the first layer takes "
                         f"{plans[0].matrix.shape[0]}")
    fan_out = [np.diff(p.matrix.indptr) for p in plans]
    rec_fan = [None if p.recurrent is None else np.diff(p.recurrent.indptr) for p in plans]
    u = [np.zeros((n, p.size)) for p in plans]
    v = [np.zeros((n, p.size)) for p in plans]
    s = [np.zeros((n, p.size)) for p in plans]
    spikes = np.zeros((n, len(plans)), dtype=np.int64)
    events = np.zeros(n, dtype=np.int64)
    in_spikes = np.zeros(n, dtype=np.int64)
    for t in range(steps):
        x = inputs[:, t]
        if binary_input:
            in_spikes += x.sum(axis=1).astype(np.int64)
        for k, p in enumerate(plans):
            if binary_input or k > 0:
                events += (x @ fan_out[k]).astype(np.int64)
            current = np.asarray(x @ p.matrix)
            if p.recurrent is not None:
                current += np.asarray(s[k] @ p.recurrent)
                events += (s[k] @ rec_fan[k]).astype(np.int64)
            par = p.params
            u[k] = (1.0 - par.du) * u[k] + current
            v[k] = (1.0 - par.dv) * v[k] + u[k]
            if p.kind == "integrator":
                x = v[k]
                continue
            fired = v[k] >= par.v_th
            if par.reset_mode == "subtract":
                v[k] = v[k] - par.v_th * fired
            else:
                v[k] = np.where(fired, par.reset_value, v[k])
            s[k] = fired.astype(np.float64)
            spikes[:, k] += fired.sum(axis=1)
            x = s[k]
    macs = 0 if binary_input else steps * plans[0].matrix.nnz
    return ForwardResult(scores=v[-1], spikes=spikes, input_spikes=in_spikes,
                         synaptic_events=events, macs=macs)


def classify(op: Classifier, weights: Mapping[str, np.ndarray], rois: np.ndarray,
             node_id: str = "classifier") -> ForwardResult:
    """Classify ROI sequences ``(n, T, H, W)`` (axes: batch, time, ``op.map_axes``).

    Parameters
    ----------
    op : Classifier
        The op with its layers.
    weights : mapping of str to ndarray
        Its weights (see :meth:`Classifier.weight_shapes`).
    rois : ndarray, shape (n, T, H, W)
        The ROI sequences.
    node_id : str
        Named in errors.

    Returns
    -------
    ForwardResult

    Raises
    ------
    IRError
        For weights that do not fit the op (see :func:`build_layer_plan`).
    """
    rois = np.asarray(rois, dtype=np.float64)
    plans = build_layer_plan(op, weights, rois.shape[-2:], node_id)
    return run_plan(plans, encode_frames(op, rois), binary_input=op.encoding.kind == "levels")


def evaluate_classifier(node_id: str, op: Classifier, args: list[np.ndarray],
                        types: list[TensorType]) -> np.ndarray:
    """The ``classifier`` op's reference implementation (:meth:`Classifier.evaluate`).

    The batch axes' ROI sequences are classified with :func:`classify` and the
    weights file the op names; the scores keep the batch axes, then ``class``.

    Raises
    ------
    IRError
        For an opaque classifier (no ``layers``), naming the node.
    """
    if not op.layers:
        raise IRError(
            f"node {node_id!r} (classifier): classifier evaluation is not implemented yet for "
            "an opaque classifier (no 'layers'); declare its layer stack and weights "
            "(docs/classifier.md) or evaluate the graph up to its input instead",
            node=node_id,
        )
    t = types[0]
    batch = op.batch_axes(t)
    order = [t.index(a) for a in (*batch, op.time_axis, *op.map_axes)]
    x = np.transpose(args[0], order)
    lead = x.shape[: len(batch)]
    rois = x.reshape(-1, *x.shape[len(batch):])
    scores = classify(op, load_weights(op, rois.shape, node_id), rois, node_id).scores
    return scores.reshape(*lead, op.num_classes)
