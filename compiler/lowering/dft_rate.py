r"""The ``rate`` motif of ``dft`` / ``linear``: a two-ReLU rate-coded spiking DFT
(López-Randulfe et al. 2021, §2.1).

One complex output bin is four non-leaky IF neurons on the trailing ``part``
axis, carrying :math:`\mathrm{relu}(\pm\mathrm{Re}\,y)` and
:math:`\mathrm{relu}(\pm\mathrm{Im}\,y)` (``re_im_signed``); a signed real input
is two regular spike trains (``signed``), a complex one four.  With ``W`` the
node's complex matrix (:func:`~compiler.lowering.dft_common.op_weights`) and
``M`` its real form (:func:`~compiler.lowering.dft_common.real_weights`), the
neuron of output part ``q`` integrates

.. math::

    u[t] = \sum_{(l,p)} M_{(l,p),(k,q)}\, s_{lp}[t], \qquad
    v[t] = v[t-1] + u[t] + b[t], \qquad
    s[t] = [v[t] \ge v_{th}], \; v \leftarrow v - v_{th}

(instantaneous current, no leak, reset by subtraction, ``b = v_th/2`` on step 0
only, so counts round to nearest).  Every population carries its value as a
*rate*: value = ``scale`` × spikes per step.  If the input parts have
``scale`` :math:`s_{in}` (encoder: :math:`s_{in} = X / r_{in}` for range ``X``
and peak rate :math:`r_{in}`), the mean drive of part ``q`` is
:math:`\mathrm{Re}(d_q y_k)/s_{in}` per step, so its count over ``T`` steps is
:math:`c_q \approx T\,\mathrm{relu}(\mathrm{Re}(d_q y_k)) / (s_{in} v_{th})`.
Choosing :math:`v_{th} = Y / (s_{in}\, r_{out})` for an output bound ``Y``
(largest :math:`|\mathrm{Re}|, |\mathrm{Im}|`) puts the busiest neuron at
:math:`r_{out}` spikes per step and gives the output scale
:math:`s_{out} = s_{in} v_{th} = Y / r_{out}`; the count decoder reads

.. math:: \hat y_k = \frac{s_{out}}{T}\big[(c_{+Re} - c_{-Re}) + i\,(c_{+Im} - c_{-Im})\big].

Bounds: ``X`` and ``Y`` come from the calibrate pass (``ctx.calibration``,
times the option ``headroom``) when it ran — :data:`OUTPUT_RATE` below 1 leaves
room for drives beyond the calibration set —; otherwise ``X`` is the compile option
``input_range`` (default 1.0: inputs normalised to ``[-1, 1]``, as the authors
min–max normalise) and ``Y`` the worst case of the weights,
:math:`Y = X \max_{k,q} \sum_{l,c} \max_{\pm} |M_{(l,c,\pm),(k,q)}|` — never
saturating, at the price of resolution.

The 2-D form needs no host boundary: a ``dft`` whose input is a ``rate``
spike value of the same network reads that population's ± trains directly
(its contract axes are ``(axis, part)`` of the ``re_im_signed`` source).

Step only: reset by subtraction makes the closed-form engine inapplicable
(``simulate(..., mode="auto")`` runs ``step``).  Weights are stored once and
shared over the repetition axes, so a 128 × 1024 frame needs one
2048 × 2048 matrix.

Examples
--------
>>> import numpy as np
>>> from ir import Graph
>>> from compiler.lowering import LoweringContext, LoweringRegistry, lower_graph
>>> from compiler.lowering.inputs import register_io
>>> g = Graph.from_dict({"name": "r", "nodes": [
...     {"id": "x", "op": "input", "shape": {"sample": 8}},
...     {"id": "f", "op": "dft", "input": "x", "axis": "sample", "out_axis": "bin"},
...     {"id": "o", "op": "output", "input": "f"}]})
>>> reg = LoweringRegistry(); register_io(reg); register_rate(reg)
>>> from compiler.compile import motif_settings
>>> ctx = LoweringContext(graph=g, registry=reg, motifs={"dft": "rate"},
...                       settings=motif_settings({"time_steps": 2000}))
>>> net = lower_graph(ctx)[0].network
>>> net.population["f/out"].shape, net.n_steps
({'bin': 8, 'part': 4}, 2000)
>>> from backends.reference import simulate
>>> x = np.cos(2 * np.pi * np.arange(8) / 8)
>>> y = simulate(net, {"x": x}).outputs["f"]
>>> bool(np.abs(y - np.fft.fft(x)).max() < 0.02)
True
"""

from __future__ import annotations

import numpy as np

from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_common import dft_axes, op_weights, real_weights
from compiler.lowering.options import RateOptions
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.values import SpikeValue, Value
from compiler.snn import Decoder, NeuronParams, PartLayout, Phase, RateCode
from ir.errors import CompileError
from ir.ops import DFT, Linear, Op

__all__ = [
    "MOTIF",
    "DEFAULT_STEPS",
    "INPUT_RATE",
    "OUTPUT_RATE",
    "INPUT_PHASE",
    "register_rate",
    "lower_rate",
    "rate_threshold",
    "worst_case_bound",
    "calibrated_bound",
    "normalize_axes_of",
]

#: Motif name in the registry and the compile option ``motifs``.
MOTIF = "rate"
#: Steps of the frame when the option ``time_steps`` is not given.
DEFAULT_STEPS = RateOptions().time_steps  # declared in compiler.lowering.options
#: Spikes per step of an encoded input at its range ``X``.
INPUT_RATE = 0.5
#: Spikes per step of the busiest output neuron at its bound ``Y``.
OUTPUT_RATE = 0.5
#: Phase of every input train (0.5: counts are ``round(n·r)``, not ``floor``).
INPUT_PHASE = 0.5


def register_rate(registry: LoweringRegistry) -> None:
    """Register :func:`lower_rate` as motif ``rate`` of ``dft`` and ``linear`` (not the default).

    Examples
    --------
    >>> reg = LoweringRegistry()
    >>> register_rate(reg)
    >>> reg.motifs(DFT), reg.default_motif(DFT)
    (['host', 'rate'], 'host')
    """
    for op_type in (DFT, Linear):
        registry.register(op_type, MOTIF, lower_rate)


def calibrated_bound(ctx: LoweringContext, node: str) -> float | None:
    """The calibrate pass's bound on ``|Re|`` and ``|Im|`` of ``node``'s value, or None.

    Reads ``ctx.calibration[node]`` (a :class:`compiler.calibration.NodeCalibration`
    or a mapping): ``max_part``, else ``max(max_re, max_im)``, times the compile
    option ``headroom`` (default 1).

    Under the ``per-input`` policy the record holds normalised values, and the
    encoder normalises at run time (:func:`normalize_axes_of`).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> ctx = SimpleNamespace(calibration={"x": {"max_re": 3.0, "max_im": 2.0}},
    ...                       settings_of=lambda model: model())
    >>> calibrated_bound(ctx, "x"), calibrated_bound(ctx, "y") is None
    (3.0, True)
    """
    rec = (ctx.calibration or {}).get(node)
    if rec is None:
        return None

    def get(name: str):
        return rec.get(name) if isinstance(rec, dict) else getattr(rec, name, None)

    bound = get("max_part")
    if bound is None and get("max_re") is not None:
        bound = max(get("max_re"), get("max_im") or 0.0)
    if not bound or bound <= 0:
        return None
    return float(bound) * ctx.settings_of(RateOptions).headroom


def normalize_axes_of(ctx: LoweringContext, node: str) -> tuple[str, ...]:
    """The axes the ``per-input`` policy normalises ``node``'s value over (``()`` if static).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> normalize_axes_of(SimpleNamespace(calibration={"x": {"normalize_axes": ["sample"]}}), "x")
    ('sample',)
    """
    rec = (ctx.calibration or {}).get(node)
    axes = (rec.get("normalize_axes") if isinstance(rec, dict)
            else getattr(rec, "normalize_axes", None)) if rec is not None else None
    return tuple(axes or ())


def worst_case_bound(m: np.ndarray, in_split: PartLayout, x_bound: float) -> float:
    r"""The largest ``|Re|``/``|Im|`` an output can reach when every input part is ``<= x_bound``.

    .. math:: Y = X \max_{k,q} \sum_{l,c} \max_{\pm} |M_{(l,c,\pm),(k,q)}|

    (of a ± pair at most one part is non-zero).

    Examples
    --------
    >>> m = real_weights(np.array([[1.0, 1.0], [1.0, -1.0]], complex), "signed", "re_im_signed")
    >>> worst_case_bound(m, "signed", 3.0)
    6.0
    """
    n_pairs = {"signed": 1, "re_im_signed": 2}[in_split]
    a = np.abs(m).reshape(-1, n_pairs, 2, m.shape[1]).max(axis=2)
    return float(x_bound * a.sum(axis=(0, 1)).max())


def rate_threshold(y_bound: float, scale_in: float, out_rate: float = OUTPUT_RATE) -> float:
    r"""``v_th = Y / (s_in · r_out)``: the output bound ``Y`` fires ``r_out`` spikes per step.

    Examples
    --------
    >>> rate_threshold(y_bound=64.0, scale_in=2.0, out_rate=0.5)
    64.0
    """
    return float(y_bound / (scale_in * out_rate))


def _steps(ctx: LoweringContext, node: str) -> int:
    steps = ctx.settings_of(RateOptions).time_steps
    if steps < 2:
        raise CompileError(f"node {node!r} (rate): time_steps={steps} is too short; a rate code "
                           f"needs many steps (default {DEFAULT_STEPS})", node=node)
    return steps


def _rate_input(ctx: LoweringContext, node: str, value: Value, steps: int):
    """The source population, its split, value scale and bound (read directly or encoded)."""
    code = value.code if isinstance(value, SpikeValue) else {}
    if (isinstance(value, SpikeValue) and value.network == ctx.network_index
            and code.get("kind") == MOTIF and code.get("steps") == steps):
        return value.population, "re_im_signed", code["scale"], code["bound"]
    split: PartLayout = "re_im_signed" if ctx.types[value.node].complex else "signed"
    found = calibrated_bound(ctx, value.node)
    x_bound = found if found else ctx.settings_of(RateOptions).input_range
    rate_code = RateCode(x_min=0.0, x_max=x_bound, max_rate=INPUT_RATE, phase=INPUT_PHASE)
    pop = ctx.encode(value, consumer=node, code=rate_code, split=split, motif=MOTIF,
                     normalize_axes=normalize_axes_of(ctx, value.node))
    return pop.id, split, x_bound / INPUT_RATE, x_bound


def lower_rate(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> SpikeValue:
    """Lower one ``dft``/``linear`` node to a two-ReLU rate-coded layer (module docstring).

    Parameters
    ----------
    ctx : LoweringContext
        Options read: ``time_steps`` (frame length ``T``, default :data:`DEFAULT_STEPS`),
        ``input_range`` (encoder range without calibration, default 1.0).
    node : str
        The node id.
    op : DFT or Linear
        Its op (a ``dft``'s folded ``window`` is part of its weights).
    inputs : list of Value
        The one input value; a ``rate`` spike value of the open network is read directly.

    Returns
    -------
    SpikeValue
        Population ``<node>/out`` (output axes + ``part`` of 4), a ``count`` decoder with
        ``combine="re_im_signed"``, window ``(0, T)`` and code ``{"kind": "rate", "scale",
        "bound", "max_rate", "steps"}``.

    Raises
    ------
    CompileError
        For ``time_steps < 2`` or an op without a weight matrix.
    """
    (value,) = inputs
    steps = _steps(ctx, node)
    axes = dft_axes(node, op, ctx.types[value.node])
    w = op_weights(op, axes.n_in, node=node)
    source, split, scale_in, x_bound = _rate_input(ctx, node, value, steps)
    m = real_weights(w, split, "re_im_signed")
    found = calibrated_bound(ctx, node)
    y_bound = found if found else worst_case_bound(m, split, x_bound)
    v_th = rate_threshold(y_bound, scale_in)
    params = NeuronParams(du=1.0, dv=0.0, v_th=v_th, reset="subtract",
                          phases=(Phase(start_step=0, bias=v_th / 2), Phase(start_step=1)))
    b = ctx.builder()
    out = b.population(node, "out", axes.out_shape(ctx.types[node], "re_im_signed"), params,
                       motif=MOTIF)
    b.matrix(node, "w", source, out.id, contract=axes.contract(split),
             produce=axes.produce("re_im_signed"), weights=m, motif=MOTIF)
    scale_out = y_bound / OUTPUT_RATE
    decoder = Decoder(port=node, population=out.id, kind="count", scale=scale_out / steps,
                      combine="re_im_signed", node=node)
    return ctx.spike_value(node, out, decoder, (0, steps), kind=MOTIF, scale=scale_out,
                           bound=y_bound, max_rate=OUTPUT_RATE, steps=steps,
                           calibrated=found is not None)
