r"""What the ``calibrate`` pass decides: value ranges per node, and the policy that produced them.

Per IR node, a :class:`NodeCalibration` records the range of its value over
the calibration set (or the worst case propagated from declared input
bounds): ``max |Re|``, ``max |Im|``, ``max |x|``, ``max (|Re| + |Im|)``, the
real parts' min and max, and quantiles of the ``|Re|, |Im|`` parts and of
``|x|`` (what a companding charging schedule is fitted to).  The motifs set
encoder ranges and thresholds from ``max_part · headroom`` with

.. math:: \text{max\_part} = \max(\max|\mathrm{Re}\,x|, \max|\mathrm{Im}\,x|).

*Axis profiles* (for per-bin stage gains, see :mod:`compiler.lowering.stage_gains`):
for every axis ``a`` of a measured node, ``axis_max[a][i]`` is the largest part
``p = max(|Re x|, |Im x|)`` at index ``i`` of ``a`` (over all other axes and
frames), and ``axis_quantiles[a]`` are the quantiles of the ``|Re|, |Im|`` parts
each divided by the maximum of its index,

.. math:: \hat p = p / m_i, \qquad m_i = \texttt{axis\_max[a][i]}

(``0`` where ``m_i = 0``): the shape of the values once every index is scaled
to the same maximum, which a stage with per-index gains ``g_i ∝ 1/m_i`` sees.

Examples
--------
>>> import numpy as np
>>> c = measure("x", np.array([3.0 - 4.0j, -1.0 + 0.5j]))
>>> c.max_re, c.max_im, c.max_abs, c.max_l1, c.max_part
(3.0, 4.0, 5.0, 7.0, 4.0)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Literal

import numpy as np

from compiler.snn.coding import split_values
from ir.errors import BudgetError, CompileError
from ir.limits import MAX_VALUE_BYTES, check_value_sizes

__all__ = ["N_QUANTILES", "NodeCalibration", "Calibration", "measure", "Policy", "SYNTHETIC",
           "synthetic_inputs"]

#: Number of quantiles kept per node (0 %, 1/256, …, 100 %).
N_QUANTILES = 257

Policy = Literal["static", "per-input"]


@dataclass(frozen=True)
class NodeCalibration:
    """The value range of one IR node (value units of the IR, after any normalisation).

    Parameters
    ----------
    node : str
        IR node id.
    max_re, max_im, max_abs, max_l1 : float
        Largest ``|Re x|``, ``|Im x|``, ``|x|`` and ``|Re x| + |Im x|``.
    min, max : float
        Smallest and largest real part.
    part_quantiles, abs_quantiles : tuple of float
        :data:`N_QUANTILES` quantiles of the pooled ``|Re|, |Im|`` values and of ``|x|``
        (empty when derived from bounds).
    normalize_axes : tuple of str
        For a graph input under ``per-input``: the axes its encoder normalises over.
    source : {"inputs", "bounds"}
        Measured on calibration inputs, or propagated from declared input bounds.
    axis_max : dict of str to tuple of float
        Per axis, the largest part at each index (empty when derived from bounds).
    axis_quantiles : dict of str to tuple of float
        Per axis, :data:`N_QUANTILES` quantiles of the parts divided by their index's
        maximum (the part values under per-index gains ``1/m``).
    second_moments : dict of str to ndarray
        Per axis a linear consumer contracts (integer targets only): ``E[p pᵀ]`` of the
        ± part vectors along it, rows ``(index, part)`` — what
        :func:`compiler.quantize_weights.rint_feedback` rounds the layer's weights against.
    frame_peaks : tuple of float
        The largest part of each calibration frame (empty from bounds or unframed values):
        the spread a new frame may show (:func:`compiler.lowering.time_inputs.encoder_headroom`).
    frames : ndarray, optional
        For a graph input measured on calibration inputs: the calibration values
        themselves (frames first, after any ``per-input`` normalisation), for the
        lowering's measured choices (:func:`compiler.lowering.time_inputs.input_rounding`).
        Compile-time only, like ``second_moments``.
    """

    node: str
    max_re: float
    max_im: float
    max_abs: float
    max_l1: float
    min: float
    max: float
    part_quantiles: tuple[float, ...] = ()
    abs_quantiles: tuple[float, ...] = ()
    normalize_axes: tuple[str, ...] = ()
    source: Literal["inputs", "bounds"] = "inputs"
    axis_max: dict[str, tuple[float, ...]] = field(default_factory=dict)
    axis_quantiles: dict[str, tuple[float, ...]] = field(default_factory=dict)
    second_moments: dict[str, np.ndarray] = field(default_factory=dict, compare=False,
                                                  repr=False)
    frame_peaks: tuple[float, ...] = ()
    frames: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def max_part(self) -> float:
        """``max(max_re, max_im)``: the full scale of one ``part`` neuron."""
        return max(self.max_re, self.max_im)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        d = asdict(replace(self, second_moments={}, frames=None))
        d.pop("second_moments", None)  # compile-time only (matrices), not part of records
        d.pop("frames", None)
        d["part_quantiles"] = list(self.part_quantiles)
        d["abs_quantiles"] = list(self.abs_quantiles)
        d["normalize_axes"] = list(self.normalize_axes)
        d["axis_max"] = {a: list(v) for a, v in self.axis_max.items()}
        d["axis_quantiles"] = {a: list(v) for a, v in self.axis_quantiles.items()}
        return d


@dataclass
class Calibration:
    """The ``calibrate`` pass's record (``program.records["calibrate"]``).

    Parameters
    ----------
    policy : {"static", "per-input"}
        ``static``: fixed ranges, nothing adapts at run time; ``per-input``: each
        input slice is normalised by its encoder, ranges hold for normalised values.
    headroom : float
        Factor applied to the measured maxima by the motifs (>= 1 leaves room for
        inputs larger than the calibration set).
    source : {"inputs", "bounds", "none"}
        Where the ranges came from (``none``: static without inputs or bounds).
    nodes : dict of str to NodeCalibration
        Per IR node.
    n_frames : int
        Calibration frames used (0 for bounds).
    """

    policy: Policy
    headroom: float
    source: Literal["inputs", "bounds", "none"]
    nodes: dict[str, NodeCalibration] = field(default_factory=dict)
    n_frames: int = 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"policy": self.policy, "headroom": self.headroom, "source": self.source,
                "n_frames": self.n_frames, "nodes": {k: v.to_dict() for k, v in self.nodes.items()}}


def _quantiles(x: np.ndarray) -> tuple[float, ...]:
    if x.size == 0:
        return ()
    return tuple(float(v) for v in np.quantile(x, np.linspace(0, 1, N_QUANTILES)))


def _top(a: np.ndarray) -> float:
    return float(a.max()) if a.size else 0.0


def _axis_profiles(parts: np.ndarray, re: np.ndarray, im: np.ndarray | None,
                   axes: tuple[str, ...]) -> tuple[dict, dict]:
    """``axis_max`` and ``axis_quantiles`` of values with a leading frames axis."""
    maxima, quantiles = {}, {}
    for k, axis in enumerate(axes, start=1):
        other = tuple(j for j in range(parts.ndim) if j != k)
        m = parts.max(axis=other)
        shape = [1] * parts.ndim
        shape[k] = m.size
        inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0).reshape(shape)
        pooled = [re * inv] + ([] if im is None else [im * inv])
        maxima[axis] = tuple(float(x) for x in m)
        quantiles[axis] = _quantiles(np.concatenate([p.ravel() for p in pooled]))
    return maxima, quantiles


def measure(node: str, values: np.ndarray, *, normalize_axes: tuple[str, ...] = (),
            axes: tuple[str, ...] = ()) -> NodeCalibration:
    """The :class:`NodeCalibration` of ``values`` (all calibration frames of one node).

    Parameters
    ----------
    node : str
        IR node id.
    values : ndarray
        Real or complex values (any shape).
    normalize_axes : tuple of str
        Recorded as is (for per-input inputs).
    axes : tuple of str
        Names of the trailing axes of ``values`` (the node's IR axes; a leading
        frames axis may precede them); gives ``axis_max``/``axis_quantiles``.
        Empty: no axis profiles.

    Returns
    -------
    NodeCalibration

    Examples
    --------
    >>> measure("x", np.array([-2.0, 1.0])).min, measure("x", np.array([-2.0, 1.0])).max_abs
    (-2.0, 2.0)
    >>> c = measure("x", np.array([[[4.0, -1.0], [2.0, 0.5j]]]), axes=("chirp", "range"))
    >>> c.axis_max
    {'chirp': (4.0, 2.0), 'range': (4.0, 1.0)}
    """
    v = np.asarray(values)
    re, im = np.abs(np.real(v)).astype(np.float64), np.abs(np.imag(v)).astype(np.float64)
    mag = np.abs(v).astype(np.float64)
    cplx = np.iscomplexobj(v)
    parts = np.concatenate([re.ravel(), im.ravel()]) if cplx else re.ravel()
    profiles: tuple[dict, dict] = ({}, {})
    if axes and v.size:
        framed = v.ndim == len(axes) + 1
        if not framed and v.ndim != len(axes):
            raise CompileError(f"calibration of {node!r}: values of shape {v.shape} do not have "
                               f"the axes {axes} (optionally after a frames axis)", node=node)
        r, i = (re, im) if framed else (re[None], im[None])
        profiles = _axis_profiles(np.maximum(r, i), r, i if cplx else None, tuple(axes))
        peaks = tuple(float(p) for p in np.maximum(r, i).reshape(r.shape[0], -1).max(axis=1))
    else:
        peaks = ()
    return NodeCalibration(node=node, max_re=_top(re), max_im=_top(im), max_abs=_top(mag),
                           max_l1=_top(re + im), min=float(np.real(v).min()) if v.size else 0.0,
                           max=float(np.real(v).max()) if v.size else 0.0,
                           part_quantiles=_quantiles(parts), abs_quantiles=_quantiles(mag.ravel()),
                           normalize_axes=tuple(normalize_axes), axis_max=profiles[0],
                           axis_quantiles=profiles[1], frame_peaks=peaks)


def _amplitude(rng: np.random.Generator, shape: tuple[int, ...], cplx: bool) -> np.ndarray:
    """Unit-variance Gaussian noise (complex: circular, unit total variance)."""
    x = rng.standard_normal(shape)
    return (x + 1j * rng.standard_normal(shape)) / np.sqrt(2.0) if cplx else x


def _power(rng: np.random.Generator, shape: tuple[int, ...], cplx: bool) -> np.ndarray:
    """``|z|²`` of unit complex Gaussian noise: exponential with mean 1, never negative."""
    return rng.standard_exponential(shape)


def _db(rng: np.random.Generator, shape: tuple[int, ...], cplx: bool) -> np.ndarray:
    """That power in decibels, ``10·log10(p)`` (floored at -300 dB)."""
    return 10.0 * np.log10(np.maximum(_power(rng, shape, cplx), 1e-30))


def _mask(rng: np.random.Generator, shape: tuple[int, ...], cplx: bool) -> np.ndarray:
    """Fair coin flips."""
    return rng.random(shape) < 0.5


#: Noise generators by input domain: ``draw(rng, shape, complex) -> ndarray``.
SYNTHETIC: dict[str, Callable[[np.random.Generator, tuple[int, ...], bool], np.ndarray]] = {
    "amplitude": _amplitude, "power": _power, "db": _db, "mask": _mask}


def synthetic_inputs(graph, *, seed: int = 0,
                     generators: Mapping[str, Callable[..., np.ndarray]] = SYNTHETIC,
                     max_memory_bytes: int | None = MAX_VALUE_BYTES) -> dict[str, np.ndarray]:
    r"""Seeded noise for every input node of ``graph``, drawn in the input's domain.

    A stand-in calibration set for when only the *cost* of a chain matters
    (``radarsnn compile/report/emit`` without ``--calibration``): every neuron,
    synapse, step and core count is independent of the values, but thresholds
    calibrated on noise say nothing about accuracy on radar data.  Per domain
    (:data:`SYNTHETIC`):

    ==========  ===============================================================
    amplitude   :math:`x \sim \mathcal N(0, 1)`; complex :math:`(a + ib)/\sqrt2`
    power       :math:`p = |z|^2 \sim \mathrm{Exp}(1)` (unit complex Gaussian noise)
    db          :math:`10 \log_{10} p` (mean ≈ -2.5 dB, standard deviation ≈ 5.6 dB)
    mask        :math:`\mathrm{Bernoulli}(1/2)` booleans
    ==========  ===============================================================

    Parameters
    ----------
    graph : ir.Graph
        The chain.
    seed : int
        Seed of ``numpy.random.default_rng``.
    generators : mapping of domain to callable
        ``draw(rng, shape, complex) -> ndarray`` per domain (default :data:`SYNTHETIC`).
    max_memory_bytes : int or None
        Limit on the bytes of the inputs drawn, checked from their types first (default
        :data:`ir.limits.MAX_VALUE_BYTES`; ``None``: no limit).

    Returns
    -------
    dict of str to ndarray
        One array per input node id, of its declared shape (no frames axis).

    Raises
    ------
    CompileError
        For an input whose domain has no generator (naming the node and the
        domain, and suggesting ``--calibration``).
    BudgetError
        If the inputs would take more than ``max_memory_bytes`` (an axis of 2**62),
        naming the largest.

    Examples
    --------
    >>> from ir import Graph
    >>> g = Graph.from_dict({"name": "x", "nodes": [
    ...     {"id": "adc", "op": "adc_input", "shape": {"chirp": 2, "sample": 4}, "complex": True},
    ...     {"id": "rd", "op": "input", "shape": {"range": 3}, "domain": "power"},
    ...     {"id": "o", "op": "output", "input": "adc"},
    ...     {"id": "p", "op": "output", "input": "rd"}]})
    >>> x = synthetic_inputs(g)
    >>> x["adc"].shape, x["adc"].dtype, bool((x["rd"] >= 0).all())
    ((2, 4), dtype('complex128'), True)
    """
    rng = np.random.default_rng(seed)
    types = graph.infer_types()
    check_value_sizes(graph, types, graph.input_ids(), max_memory_bytes=max_memory_bytes,
                      error=BudgetError, doing="drawing synthetic calibration inputs")
    out = {}
    for node in graph.input_ids():
        t = types[node]
        if t.domain not in generators:
            raise CompileError(f"input {node!r}: no synthetic calibration for domain "
                               f"{t.domain!r} (known: {sorted(generators)}); pass calibration "
                               "inputs (--calibration NODE=X.npy)", node=node)
        out[node] = generators[t.domain](rng, tuple(t.axes.values()), bool(t.complex))
    return out


#: Largest part vector (index × parts) whose second moment calibration keeps (32 MB).
MAX_MOMENT_ROWS = 2048


def second_moment(values: np.ndarray, axis: int, split: str) -> np.ndarray | None:
    """``E[p pᵀ]`` of the ± part vectors of ``values`` along ``axis`` (rows ``(index, part)``).

    Parameters
    ----------
    values : ndarray
        Calibration values, any leading frames axis included.
    axis : int
        The contracted axis.
    split : str
        The encoder's part split (``signed`` for real, ``re_im_signed`` for complex).

    Returns
    -------
    ndarray or None
        ``(n·P, n·P)``; None beyond :data:`MAX_MOMENT_ROWS` rows.

    Examples
    --------
    >>> second_moment(np.array([[1.0, -2.0]]), axis=1, split="signed").tolist()
    [[1.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 4.0]]
    """

    parts = split_values(np.moveaxis(np.asarray(values), axis, -1), split)
    rows = parts.shape[-2] * parts.shape[-1]
    if rows > MAX_MOMENT_ROWS:
        return None
    v = parts.reshape(-1, rows)
    return (v.T @ v) / max(1, v.shape[0])
