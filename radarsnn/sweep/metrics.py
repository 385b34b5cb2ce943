r"""Accuracy metrics of a sweep, as additive per-frame sums and a final formula.

A :class:`Metric` has two pure functions: ``update(frame) -> dict`` gives one
frame's **additive** statistics (counts, sums) and ``finalize(sums) -> dict`` turns
their sums over every frame of a point into the figures.  Sums over slices are
taken in frame order, so a point's figures do not depend on which worker ran
which cell.  Metrics are looked up by name in a :class:`MetricRegistry` passed
to the runner (:func:`default_metrics` holds the built-in ones).

Built-in metrics
----------------
``cfar``
    Spiking decisions ``s`` vs the conventional CFAR ``c`` (``ir.evaluate``) on the
    same frame (Vogginger et al. 2022, Eq. 13-14), pooled over all cells of all frames:

    .. math:: \text{sensitivity} = \frac{TP}{TP+FN},\quad
              \text{precision} = \frac{TP}{TP+FP}

    with ``TP = Σ s∧c``, ``FN = Σ ¬s∧c``, ``FP = Σ s∧¬c`` (1.0 when the denominator is 0).
``detection``
    Against the scene's ground truth: a target is hit when a detection lies within
    ``tolerance_bins`` (default 1) of its (range, Doppler) bin (Doppler wraps);
    ``pd = hits / targets`` for the spiking and the conventional decisions, and
    ``false_alarms_per_frame`` = detections near no target, per frame (leakage and
    clutter returns count: compare with ``false_alarms_per_frame_conventional``).
``sft_rmse``
    :func:`compiler.lowering.dft_common.sft_rmse` of the node's value against the
    reference (S-FT accuracy protocol), averaged over frames; option ``n_fft``.
``classifier_accuracy``
    The hook the classifier issue fills: ``argmax`` of the node's scores (last axis)
    against the frame's label; ``accuracy = correct / frames``.

Examples
--------
>>> sensitivity_precision(tp=3, fn=1, fp=0)
(0.75, 1.0)
>>> m = default_metrics()["cfar"]
>>> s = np.array([[1.0, 0.0], [1.0, 1.0]]); c = np.array([[True, True], [False, True]])
>>> counts = m.update(FrameData(values={"det": s}, reference={"det": c}, node="det"))
>>> counts
{'tp': 2, 'fn': 1, 'fp': 1}
>>> m.finalize(counts)
{'sensitivity': 0.6666666666666666, 'precision': 0.6666666666666666, 'tp': 2, 'fn': 1, 'fp': 1}
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ir.errors import SimulationError

__all__ = ["FrameData", "Metric", "MetricRegistry", "default_metrics", "sensitivity_precision",
           "detection_counts", "NODE_OPS"]

#: The op a metric's ``node`` defaults to (the graph's only node of that op).
NODE_OPS = {"cfar": "cfar", "detection": "cfar", "sft_rmse": "dft", "classifier_accuracy": None}


@dataclass(frozen=True)
class FrameData:
    """What a metric sees of one frame.

    Attributes
    ----------
    values : dict
        The compiled program's value of each needed node.
    reference : dict
        The golden value (``ir.evaluate`` of the original chain) of each needed node.
    node : str
        The node the metric reads.
    axes : tuple of str
        The node's axis names, in order.
    truth : tuple
        The scene's :class:`radar.scene.TargetTruth` records (empty for files).
    label : int or None
        The frame's class label, when the source has labels.
    options : dict
        The metric's options from the spec.
    seed : int
        The cell's seed (derived from the cell id), for metrics that draw.
    """

    values: Mapping[str, np.ndarray]
    reference: Mapping[str, np.ndarray]
    node: str
    axes: tuple[str, ...] = ()
    truth: tuple = ()
    label: int | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    seed: int = 0


@dataclass(frozen=True)
class Metric:
    """A metric: per-frame additive statistics and the formula applied to their sums."""

    name: str
    update: Callable[[FrameData], dict[str, float]]
    finalize: Callable[[dict[str, float]], dict[str, float]]
    doc: str = ""


class MetricRegistry:
    """Metrics by name; pass one to :func:`radarsnn.sweep.run.run_sweep`.

    Examples
    --------
    >>> reg = MetricRegistry()
    >>> reg.register(Metric("frames", lambda f: {"n": 1}, lambda s: s))
    >>> sorted(reg), reg["frames"].finalize({"n": 4})
    (['frames'], {'n': 4})
    """

    def __init__(self) -> None:
        self._metrics: dict[str, Metric] = {}

    def register(self, metric: Metric, *, replace: bool = False) -> None:
        """Add ``metric``; ``replace=True`` overrides one of the same name."""
        if metric.name in self._metrics and not replace:
            raise SimulationError(f"metric {metric.name!r} is already registered; pass "
                                  "replace=True to override it")
        self._metrics[metric.name] = metric

    def __getitem__(self, name: str) -> Metric:
        if name not in self._metrics:
            raise SimulationError(f"metric {name!r} is not registered; known: "
                                  f"{sorted(self._metrics)}")
        return self._metrics[name]

    def __contains__(self, name: object) -> bool:
        return name in self._metrics

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(self._metrics))


def sensitivity_precision(*, tp: int, fn: int, fp: int) -> tuple[float, float]:
    """``(TP/(TP+FN), TP/(TP+FP))``, each 1.0 when its denominator is 0."""
    return (tp / (tp + fn) if tp + fn else 1.0, tp / (tp + fp) if tp + fp else 1.0)


# ---------------------------------------------------------------------------- cfar

def _cfar_update(f: FrameData) -> dict[str, float]:
    s = np.asarray(f.values[f.node]) > 0.5
    c = np.asarray(f.reference[f.node]) > 0.5
    return {"tp": int(np.sum(s & c)), "fn": int(np.sum(~s & c)), "fp": int(np.sum(s & ~c))}


def _cfar_finalize(sums: dict[str, float]) -> dict[str, float]:
    sens, prec = sensitivity_precision(tp=sums["tp"], fn=sums["fn"], fp=sums["fp"])
    return {"sensitivity": sens, "precision": prec, **sums}


# ---------------------------------------------------------------------------- detection

def detection_counts(det: np.ndarray, bins: np.ndarray, tolerance: int) -> tuple[int, int, int]:
    """``(hits, detections, detections near a target)`` of one ``[range, doppler]`` mask.

    ``bins`` is ``(n_targets, 2)`` (range bin, Doppler bin); "near" means within
    ``tolerance`` bins along both axes, range clipped and Doppler wrapped.

    Examples
    --------
    >>> det = np.zeros((8, 4), bool); det[2, 0] = det[7, 3] = True
    >>> detection_counts(det, np.array([[3, 3], [6, 1]]), 1)
    (1, 2, 1)
    """
    det = np.asarray(det, bool)
    n_range, n_dop = det.shape
    near = np.zeros_like(det)
    hits = 0
    offsets = np.arange(-tolerance, tolerance + 1)
    for r, d in np.asarray(bins, np.int64).reshape(-1, 2):  # one box per target
        rows = np.clip(r + offsets, 0, n_range - 1)
        cols = (d + offsets) % n_dop
        box = np.ix_(rows, cols)
        hits += int(det[box].any())
        near[box] = True
    return hits, int(det.sum()), int(np.sum(det & near))


def _range_doppler(f: FrameData, value: np.ndarray) -> np.ndarray:
    if set(f.axes) != {"range", "doppler"}:
        raise SimulationError(f"metric detection: node {f.node!r} has axes {list(f.axes)}; it "
                              "needs a [range, doppler] detection map")
    value = np.asarray(value) > 0.5
    return value if f.axes == ("range", "doppler") else value.T


def _detection_update(f: FrameData) -> dict[str, float]:
    tol = int(f.options.get("tolerance_bins", 1))
    bins = np.array([(t.range_bin, t.doppler_bin) for t in f.truth], np.int64).reshape(-1, 2)
    out = {"targets": len(bins), "frames": 1}
    for tag, value in (("", f.values[f.node]), ("_conventional", f.reference[f.node])):
        hits, dets, near = detection_counts(_range_doppler(f, value), bins, tol)
        out |= {f"hits{tag}": hits, f"detections{tag}": dets, f"near{tag}": near}
    return out


def _detection_finalize(s: dict[str, float]) -> dict[str, float]:
    out: dict[str, float] = {"targets": s["targets"]}
    for tag in ("", "_conventional"):
        out[f"pd{tag}"] = s[f"hits{tag}"] / s["targets"] if s["targets"] else 1.0
        out[f"false_alarms_per_frame{tag}"] = (s[f"detections{tag}"] - s[f"near{tag}"]) / max(
            s["frames"], 1)
    return out


# ---------------------------------------------------------------------------- sft_rmse

def _sft_update(f: FrameData) -> dict[str, float]:
    from compiler.lowering.dft_common import sft_rmse

    n_fft = f.options.get("n_fft")
    rmse = sft_rmse(np.asarray(f.values[f.node]), np.asarray(f.reference[f.node]),
                    n_fft=None if n_fft is None else int(n_fft))
    return {"rmse_sum": float(rmse), "frames": 1}


def _sft_finalize(s: dict[str, float]) -> dict[str, float]:
    return {"rmse": s["rmse_sum"] / max(s["frames"], 1)}


# ---------------------------------------------------------------------------- classifier

def _classifier_update(f: FrameData) -> dict[str, float]:
    if f.label is None:
        raise SimulationError(f"metric classifier_accuracy: the frames have no labels (node "
                              f"{f.node!r}); use a folder source with `labels: FILE.npy`")
    scores = np.asarray(f.values[f.node]).reshape(-1)
    return {"correct": int(int(np.argmax(scores)) == f.label), "frames": 1}


def _classifier_finalize(s: dict[str, float]) -> dict[str, float]:
    return {"accuracy": s["correct"] / max(s["frames"], 1)}


def default_metrics() -> MetricRegistry:
    """A fresh registry of the built-in metrics (``cfar``, ``detection``, ``sft_rmse``,
    ``classifier_accuracy``); the module docstring gives their formulas."""
    reg = MetricRegistry()
    reg.register(Metric("cfar", _cfar_update, _cfar_finalize, "spiking vs conventional CFAR"))
    reg.register(Metric("detection", _detection_update, _detection_finalize,
                        "detections vs the scene's ground truth"))
    reg.register(Metric("sft_rmse", _sft_update, _sft_finalize, "S-FT RMSE vs the exact DFT"))
    reg.register(Metric("classifier_accuracy", _classifier_update, _classifier_finalize,
                        "class argmax vs the frame's label (hook for the classifier issue)"))
    return reg
