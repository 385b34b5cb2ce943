"""The golden numpy meaning of every built-in op: :data:`EVAL_REGISTRY` (op class -> function).

An implementation gets the node id, the op, the input arrays and the input types,
and returns the node's array; arrays keep the axis order of their
:class:`~ir.types.TensorType`. The maths is delegated to :mod:`radar.dsp` and
:mod:`radar.cfar`, the golden references the spiking lowerings are checked
against (the domain is the layer below the IR: :mod:`radar` imports only
:mod:`ir.errors`). :mod:`ir.interpreter` runs a graph with them.

Examples
--------
>>> import numpy as np
>>> from ir.ops import Magnitude
>>> EVAL_REGISTRY[Magnitude]("m", Magnitude(), [np.array([3 + 4j])], []).tolist()
[5.0]
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ir.classifier_forward import classify, load_weights
from ir.errors import IRError
from ir.ops import (
    CFAR,
    DFT,
    Add,
    Classifier,
    Cluster,
    Linear,
    Log,
    Magnitude,
    Op,
    Output,
    Sum,
    Threshold,
    Track,
    Window,
)
from ir.types import TensorType
from radar.cfar import cfar
from radar.clustering import cluster_detections
from radar.dsp import dft, magnitude, to_db
from radar.tracking import track_sequence
from radar.windows import apply_window

__all__ = ["EVAL_REGISTRY", "EvalRegistry", "Implementation"]

Implementation = Callable[[str, Op, list[np.ndarray], list[TensorType]], np.ndarray]
"""``impl(node_id, op, input_arrays, input_types) -> output array``."""

EvalRegistry = Mapping[type[Op], Implementation]
"""Op class -> implementation."""


def _window(node_id: str, op: Window, args: list, types: list) -> np.ndarray:

    return apply_window(args[0], op.kind, axis=types[0].index(op.axis))


def _dft(node_id: str, op: DFT, args: list, types: list) -> np.ndarray:

    ax = types[0].index(op.axis)
    x = args[0] if op.window is None else apply_window(args[0], op.window, axis=ax)
    return dft(x, axis=ax, n_fft=op.n_fft, keep=op.keep, shift=op.shift)


def _linear(node_id: str, op: Linear, args: list, types: list) -> np.ndarray:
    matrix = np.asarray(op.matrix, dtype=np.float64)
    if op.matrix_imag is not None:
        matrix = matrix + 1j * np.asarray(op.matrix_imag, dtype=np.float64)
    ax = types[0].index(op.axis)
    return np.moveaxis(np.tensordot(matrix, args[0], axes=([1], [ax])), 0, ax)


def _sum(node_id: str, op: Sum, args: list, types: list) -> np.ndarray:
    return args[0].sum(axis=types[0].index(op.axis))


def _magnitude(node_id: str, op: Magnitude, args: list, types: list) -> np.ndarray:

    return magnitude(args[0], op.kind)


def _log(node_id: str, op: Log, args: list, types: list) -> np.ndarray:

    return to_db(args[0], domain=types[0].domain, floor_db=op.floor_db)


def _add(node_id: str, op: Add, args: list, types: list) -> np.ndarray:
    return args[0] + args[1]


def _cfar(node_id: str, op: CFAR, args: list, types: list) -> np.ndarray:

    win = op.window(node_id, types[0])
    src = [types[0].index(a) for a in win.axes]
    dst = list(range(-len(src), 0))
    moved = np.moveaxis(args[0], src, dst)
    det = cfar(
        moved,
        kind=op.kind,
        guard=list(win.guard),
        train=list(win.train),
        alpha=op.alpha_for(win.n_train),
        k=op.k,
        edge=list(win.edge),
    )
    return np.moveaxis(det, dst, src)


def _threshold(node_id: str, op: Threshold, args: list, types: list) -> np.ndarray:
    return args[0] > op.value if op.strict else args[0] >= op.value


def _output(node_id: str, op: Output, args: list, types: list) -> np.ndarray:
    return args[0]


def _cluster(node_id: str, op: Cluster, args: list, types: list) -> np.ndarray:

    maps = [types[0].index(a) for a in op.axes]
    moved = [np.moveaxis(np.asarray(a), maps, [-2, -1]) for a in args]
    # a mask decoded from spikes may arrive as 0/1 floats (run_program's host segments)
    return cluster_detections(moved[0] != 0, moved[1] if len(moved) == 2 else None,
                              eps_bins=op.eps_bins, min_samples=op.min_samples,
                              max_clusters=op.max_clusters, axes_scale=op.axes_scale,
                              wrap=op.wrap)


def _track(node_id: str, op: Track, args: list, types: list) -> np.ndarray:

    return track_sequence(args[0], **op.tracker_params())


def _classifier(node_id: str, op: Classifier, args: list, types: list) -> np.ndarray:
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


EVAL_REGISTRY: dict[type[Op], Implementation] = {
    Window: _window,
    DFT: _dft,
    Linear: _linear,
    Sum: _sum,
    Magnitude: _magnitude,
    Log: _log,
    Add: _add,
    CFAR: _cfar,
    Threshold: _threshold,
    Output: _output,
    Classifier: _classifier,
    Cluster: _cluster,
    Track: _track,
}
"""The reference implementation of every op that computes (graph inputs take the given arrays)."""
