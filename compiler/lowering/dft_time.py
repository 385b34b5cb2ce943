r"""The time-coded S-FT motif (``time``, default for ``dft``): one spike per neuron, two stages.

A *time-linear code* carries non-negative part values ``z`` by one spike each:
``z = s·(E − t)`` for a spike at step ``t < E`` (no spike: ``z = 0``), with the
code's *end* ``E`` and *scale* ``s``.  Signed and complex values use ± parts
(``signed``: ``(x⁺, x⁻)``; ``re_im_signed``: ``(Re⁺, Re⁻, Im⁺, Im⁻)``), so no value
ever needs an offset.  The encoder of a host value ``x`` uses
``LatencyCode(t_max=T, x_min=0, x_max=X)``: ``t = T − rint(z·T/X)``, i.e. ``E = T``,
``s = X/T`` (``X`` from the calibrate pass: ``max_part · headroom``, or 1 for
``per-input``, whose encoder normalises each slice).

A layer ``y = M x`` (``M`` from :func:`~compiler.lowering.dft_common.real_weights`)
is one population of non-leaky ramp neurons (``du = dv = 0``, fire-once):

* **silent stage** ``[0, E_in)``: input on, spiking off; with integer weights
  ``Q ≈ M/q`` (:mod:`compiler.quantize_weights`) the membrane ends at
  ``V = Σ Q (E_in − t) = (M ẑ)/(q s_in)`` — exact integer arithmetic;
* **charging stage** ``[E_in, E_in + T)``: input off, the bias schedule of
  :mod:`compiler.lowering.charging` (constant or companding), threshold
  ``v_th = B(T) + b_T/2``; a spike decodes to the middle of its membrane
  interval, so each output part is within ``q s_in b/2`` of ``relu(±(M ẑ))``.

With the constant schedule the output is again time-linear (``E = E_in + T``,
``s = q s_in b``): the next S-FT (the Doppler DFT after the range DFT) reads the
spikes directly, integrating until ``E`` — no host boundary.  Companding
outputs decode through a table (``spike_table``) and are used only where the
value goes to the host.  Weights, biases and thresholds are dyadic, so the
closed-form and step engines agree exactly.

**Stage gains** (option ``stage_gains``, ``auto`` | ``none``).  One full scale
per layer wastes the window on weak bins: with the Tx→Rx leakage at range 0
~60 dB over the targets, a target's range bin decodes to 0.  When the next
stage is linear along *another* axis (Doppler DFT along ``chirp`` after the
range DFT), it acts on each index ``r`` of this layer's output axis separately,
so index ``r`` may carry its own gain ``g_r > 0`` at no cost in exactness:

.. math:: \tilde y_{r} = g_r\, y_r = (G W x)_r, \qquad
          \tilde z_{\cdot r} = D\,\tilde y_{\cdot r} = g_r\, z_{\cdot r}

(``G = diag(g)`` scales the columns ``(r, part)`` of ``M``); every later stage
on the path repeats over ``r`` and keeps the gain, and the decoder of each
stage divides it out (``Decoder.gain_axis``/``gains``).  With the per-index
calibrated maxima ``m_r`` of the *first* stage (``NodeCalibration.axis_max``)

.. math:: \ell_r = \min\bigl(\max(\mu\, m_r,\; \phi\,\mathrm{median}_j m_j,\;
          \kappa\,\sigma_r),\ \max_j m_j\bigr), \qquad
          g_r = \frac{\max_j \ell_j}{\max(\ell_r,\ \max_j \ell_j / R)}, \qquad
          R = 2^{\,b - 1 - (\lceil\log_2 T\rceil + 2)}

(``μ`` = :data:`GAIN_MARGIN`, ``φ`` = :data:`GAIN_FLOOR`, ``κ`` =
:data:`GAIN_CODE_SIGMAS`, ``σ_r = s_in/√12·‖M_{·,r}‖₂`` the rms error the input
code's rounding leaves on index ``r`` — calibration runs in floats and does not
see it; the cap ``max m`` — the full scale without gains — means no index is ever
coarser than without gains; ``b`` the weight bits:
option ``weight_bits``, else the target's, else :func:`exact_weight_bits`; the
weakest-gain column keeps ``log₂ T + 2`` bits, and ``R < 2`` — 8-bit weights —
turns gains off).  Every stage ``k`` on the path gets the full scale
``headroom · max_r g_r ℓ_{k,r}`` with its own levels, so each index of the
first stage spans the whole window.  The first stage sets the gains because
its rounding errors are the ones that spread: an error on a range value is
white over the chirps and lands in every Doppler bin of that range row, while
the last stage's errors stay in their cell (and companding refines its small
values).  The margin ``μ`` covers frame-to-frame changes of a bin's maximum;
the floor ``φ`` keeps bins that are quiet on the calibration set from gains so
large that a target or scatterer appearing there later would saturate.
``auto`` applies gains when the output goes through time-coded
``dft``/``linear``/``window`` stages along other axes and then to the host only.

Examples
--------
>>> from compiler.lowering import LoweringRegistry
>>> from ir.ops import DFT
>>> reg = LoweringRegistry()
>>> register_time(reg)
>>> reg.default_motif(DFT), reg.motifs(DFT)
('time', ['host', 'time'])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from compiler.calibration import NodeCalibration
from compiler.lowering.charging import choose_schedule
from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_common import dft_axes, op_weights, real_weights
from compiler.lowering.registry import HOST, LoweringRegistry
from compiler.lowering.values import SpikeValue, Value
from compiler.quantize_weights import quantize, weight_bits_of
from compiler.snn import (
    N_PARTS,
    PART_AXIS,
    Decoder,
    Encoder,
    LatencyCode,
    NeuronParams,
    Phase,
    Population,
    Split,
)
from ir.errors import CompileError
from ir.ops import DFT, Linear, Op, Window

__all__ = ["DEFAULT_TIME_STEPS", "STAGE_GAINS", "GAIN_MARGIN", "GAIN_FLOOR",
           "GAIN_CODE_SIGMAS", "TimeCode",
           "LayerInput", "calibration_of", "headroom_of", "exact_weight_bits", "index_levels",
           "stage_gains", "time_source", "time_layer", "register_time"]

#: Charging (and encoding) window ``T`` when the ``time_steps`` option is not given.
DEFAULT_TIME_STEPS = 256
#: Values of the ``stage_gains`` option (the first is the default).
STAGE_GAINS = ("auto", "none")
#: Stage gains: level of an index over its calibrated maximum (frame-to-frame margin).
GAIN_MARGIN = 1.25
#: Stage gains: floor of the per-index levels, in medians of the per-index maxima.
GAIN_FLOOR = 4.0
#: Stage gains: floor of the per-index levels, in rms errors of the input code's rounding.
GAIN_CODE_SIGMAS = 5.0
_KIND = "time-linear"


@dataclass(frozen=True)
class TimeCode:
    """A time-linear code: part value ``scale·(end − t)`` for a spike at ``t``.

    With ``gain_axis``, the part at index ``i`` of that axis carries
    ``gains[i]`` times the value (see the module docstring).

    Examples
    --------
    >>> TimeCode(end=8, scale=0.5, split="signed").as_code()
    {'kind': 'time-linear', 'end': 8, 'scale': 0.5, 'split': 'signed'}
    >>> TimeCode(8, 0.5, "none", gain_axis="range", gains=(1.0, 2.0)).as_code()["gains"]
    [1.0, 2.0]
    """

    end: int
    scale: float
    split: Split
    gain_axis: str | None = None
    gains: tuple[float, ...] = ()

    def as_code(self) -> dict:
        """The JSON-able ``SpikeValue.code``."""
        code = {"kind": _KIND, "end": self.end, "scale": self.scale, "split": self.split}
        if self.gain_axis is not None:
            code.update(gain_axis=self.gain_axis, gains=list(self.gains))
        return code


@dataclass(frozen=True)
class LayerInput:
    """One projection into a time layer: ``source`` population, real matrix, axes."""

    source: str
    matrix: np.ndarray
    contract: tuple[str, ...]
    produce: tuple[str, ...]


def _steps(ctx: LoweringContext) -> int:
    t = int(ctx.option("time_steps", DEFAULT_TIME_STEPS))
    if t < 2:
        raise CompileError(f"time_steps={t} is too short for a time code; use >= 2 (256 typical)")
    return t


def calibration_of(ctx: LoweringContext, node: str, consumer: str) -> NodeCalibration:
    """The calibrate pass's record of ``node`` (raises a clear error without one)."""
    rec = ctx.calibration.get(node)
    if rec is None:
        raise CompileError(f"node {consumer!r}: time-coded motifs need the range of {node!r}, "
                           "which was not calibrated; run the 'calibrate' pass before 'lower' "
                           "and give calibration_inputs={input: array} or "
                           "input_bounds={input: max |value|} (or calibration='per-input')",
                           node=consumer)
    return rec


def headroom_of(ctx: LoweringContext) -> float:
    """The calibration headroom (option ``headroom``, default 1)."""
    return float(ctx.option("headroom", 1.0))


def time_source(ctx: LoweringContext, consumer: str, value: Value, *, motif: str,
                gains_ok: bool = False) -> tuple[str, TimeCode]:
    """A population carrying ``value`` in a time-linear code, and that code.

    Spikes of a time-linear value in the open network are read directly (if
    they carry stage gains, only by a consumer that handles them,
    ``gains_ok``); anything else is encoded from the host (a visible boundary)
    with the calibrated range, split into ± parts.
    """
    if (isinstance(value, SpikeValue) and value.code.get("kind") == _KIND
            and value.network == ctx.network_index and (gains_ok or not value.code.get("gains"))):
        c = value.code
        return value.population, TimeCode(int(c["end"]), float(c["scale"]), c["split"],
                                          c.get("gain_axis"), tuple(c.get("gains", ())))
    host = ctx.to_host(value)
    rec = calibration_of(ctx, host.node, consumer)
    t = _steps(ctx)
    full = rec.max_part * headroom_of(ctx) or 1.0
    split: Split = "re_im_signed" if host.type.complex else "signed"
    builder = ctx.builder()
    if builder.has_encoder(host.node):
        raise CompileError(f"node {consumer!r}: value {host.node!r} is already encoded in this "
                           "network by another consumer; give it one motif", node=consumer)
    shape = {**host.type.axes, PART_AXIS: N_PARTS[split]}
    pop = builder.population(consumer, "in", shape, motif=motif, source=True)
    builder.encoder(Encoder(port=host.node, population=pop.id, split=split, node=host.node,
                            code=LatencyCode(t_min=0, t_max=t, x_min=0.0, x_max=full),
                            normalize_axes=rec.normalize_axes))
    builder.meta["calibration"] = ctx.option("calibration", "static")
    return pop.id, TimeCode(end=t, scale=full / t, split=split)


def _allow_companding(ctx: LoweringContext, node: str) -> bool:
    """Companding only where every consumer takes the value on the host."""
    return all(ctx.motif_for(c) == HOST for c in ctx.graph.consumers_of(node))


def time_layer(ctx: LoweringContext, node: str, code_in: TimeCode, inputs: list[LayerInput], *,
               shape: dict[str, int], split: Split, full_scale: float,
               samples: tuple[float, ...] = (), motif: str = "time",
               gain_axis: str | None = None, gains: tuple[float, ...] = (),
               weight_bits: int | None = None) -> SpikeValue:
    """Add one two-stage ramp layer reading ``inputs`` (all in ``code_in``); see the module doc.

    Parameters
    ----------
    ctx : LoweringContext
    node : str
        IR node whose value the layer carries.
    code_in : TimeCode
        The code of every input population.
    inputs : list of LayerInput
        Real matrices in value units (quantized together to one scale).
    shape, split : dict, str
        Output population shape and its part split (``none``/``signed``/``re_im_signed``).
    full_scale : float
        Largest part value to represent (value units).
    samples : tuple of float
        Calibration part values (value units) to choose the charging schedule on.
    motif : str
        Motif name for provenance.
    gain_axis, gains : str or None, tuple of float
        Per-index gains the output carries (already in the matrices, the full
        scale and the samples); its decoder divides them out.
    weight_bits : int, optional
        Width to quantize to (default: option ``weight_bits`` or 24).

    Returns
    -------
    SpikeValue
        Time-linear code for the constant schedule, ``time-table`` for companding.
    """
    t = _steps(ctx)
    bits = weight_bits or weight_bits_of(ctx.option("weight_bits"), node=node)
    levels, q = quantize(np.concatenate([i.matrix.ravel() for i in inputs]), bits)
    unit = q * code_in.scale
    mode = ctx.option("charging", "auto")
    if mode != "constant" and not _allow_companding(ctx, node):
        mode = "constant"
    sched, errors = choose_schedule(t, (full_scale or 1.0) / unit,
                                    np.asarray(samples) / unit if samples else None, mode=mode)
    e_in, e_out = code_in.end, code_in.end + t
    phases = (Phase(start_step=0, spiking_on=False),
              *(Phase(start_step=e_in + s, bias=b, input_on=False)
                for s, b in zip(sched.starts, sched.biases, strict=True)),
              Phase(start_step=e_out, input_on=False, spiking_on=False))
    params = NeuronParams(du=0.0, dv=0.0, v_th=sched.v_th, reset="fire_once", phases=phases)
    builder = ctx.builder()
    pop: Population = builder.population(node, "out", shape, params, motif=motif)
    offset = 0
    for i, inp in enumerate(inputs):
        w = levels[offset:offset + inp.matrix.size].reshape(inp.matrix.shape)
        offset += inp.matrix.size
        builder.matrix(node, f"w{i}", inp.source, pop.id, contract=inp.contract,
                       produce=inp.produce, motif=motif, weights=w)
    charging = {**sched.describe(), "mse": errors, "weight_bits": bits, "unit": unit}
    builder.meta.setdefault("charging", {})[node] = charging
    gained = {"gain_axis": gain_axis, "gains": tuple(gains)} if gain_axis else {}
    if sched.kind == "constant":
        b = sched.biases[0]
        dec = Decoder(port=node, population=pop.id, kind="spike_time", scale=unit * b,
                      t_ref=float(e_out), missing=0.0, combine=split, node=node, **gained)
        code = TimeCode(end=e_out, scale=unit * b, split=split, **gained).as_code()
    else:
        dec = Decoder(port=node, population=pop.id, kind="spike_table", scale=unit,
                      table=tuple(float(v) for v in sched.levels()), t_ref=float(e_in),
                      missing=0.0, combine=split, node=node, **gained)
        code = {"kind": "time-table", "end": e_out, "split": split}
    return ctx.spike_value(node, pop, dec, (e_in, e_out), **code, charging=charging)


def _out_split(complex_out: bool) -> Split:
    return "re_im_signed" if complex_out else "signed"


def exact_weight_bits(t_steps: int, n_rows: int) -> int:
    """Widest weights (≤ 32 bits) whose membrane sums stay exact in float64.

    A silent-stage membrane is at most ``(2^{b−1} − 1)·T·n_rows`` in integer
    units; it must stay below ``2^53``.

    Examples
    --------
    >>> exact_weight_bits(256, 2048), exact_weight_bits(4096, 4096)
    (32, 30)
    """
    return min(32, 54 - math.ceil(math.log2(t_steps)) - math.ceil(math.log2(max(n_rows, 2))))


def _gain_path(ctx: LoweringContext, node: str, axis: str) -> list[str] | None:
    """``node`` and the time-coded linear stages along other axes after it, up to the host."""
    path = [node]
    while True:
        consumers = ctx.graph.consumers_of(path[-1])
        if consumers and all(ctx.motif_for(c) == HOST for c in consumers):
            return path if len(path) > 1 else None
        if len(consumers) != 1:
            return None
        (nxt,) = consumers
        op = ctx.graph.op(nxt)
        motif = ctx.motif_for(nxt)
        if ctx.registry.rule(type(op), motif, node=nxt) is not lower_time_linear or op.axis == axis:
            return None
        path.append(nxt)


def stage_gains(ctx: LoweringContext, node: str, axis: str, n_rows: int,
                code_noise: np.ndarray | None = None) -> tuple[np.ndarray, float] | None:
    """The per-index gains along ``axis`` that stage ``node`` starts, or None.

    See the module docstring for the rule and the formula.

    Parameters
    ----------
    ctx : LoweringContext
    node : str
        A time-coded linear stage whose output axis is ``axis``.
    axis : str
        The axis to gain along.
    n_rows : int
        Rows of the stage's real matrix (for :func:`exact_weight_bits`).
    code_noise : ndarray, optional
        Per index, the rms error the input code's rounding leaves on the stage's
        output (``s_in/√12 · ‖M_col‖₂``, largest part); the levels are at least
        :data:`GAIN_CODE_SIGMAS` times it, since calibration (in floats) does not see it.

    Returns
    -------
    (ndarray of float64, float) or None
        The gains ``g`` (``min g = 1``) and the gained level ``g_r ℓ_r = max ℓ`` every
        index reaches; None under ``stage_gains="none"``, when no later time-coded
        stage repeats over ``axis``, without per-axis calibration, or when the weight
        width leaves no room (``R < 2``).

    Raises
    ------
    CompileError
        For a ``stage_gains`` value other than ``auto``/``none``.
    """
    mode = ctx.option("stage_gains", STAGE_GAINS[0])
    if mode not in STAGE_GAINS:
        raise CompileError(f"node {node!r}: stage_gains={mode!r} is not a mode; use 'auto' or "
                           "'none'", node=node)
    path = _gain_path(ctx, node, axis) if mode == "auto" else None
    records = [ctx.calibration.get(n) for n in path or ()]
    if not path or any(r is None or axis not in r.axis_max for r in records):
        return None
    t = _steps(ctx)
    bits = (ctx.option("weight_bits") or getattr(ctx.target, "weight_bits", None)
            or exact_weight_bits(t, n_rows))
    ratio = 2.0 ** (bits - 1 - (math.ceil(math.log2(t)) + 2))
    if ratio < 2:
        return None
    maxima = np.asarray(records[0].axis_max[axis])
    levels = index_levels(maxima)
    if code_noise is not None:
        levels = np.maximum(levels, GAIN_CODE_SIGMAS * np.asarray(code_noise))
    if maxima.max() > 0:  # never coarser than one full scale for all (no gains)
        levels = np.minimum(levels, maxima.max())
    levels = np.maximum(levels, levels.max() / ratio)
    return levels.max() / levels, float(levels.max())


def index_levels(maxima: np.ndarray) -> np.ndarray:
    r"""Per-index levels ``ℓ_r = max(μ·m_r, φ·median m)`` of calibrated maxima ``m``.

    ``μ`` = :data:`GAIN_MARGIN`, ``φ`` = :data:`GAIN_FLOOR`.  With a zero median
    every index gets ``μ·max m`` (no gains); all zero: all ones.

    Examples
    --------
    >>> index_levels(np.array([100.0, 4.0, 3.0, 0.0])).tolist()  # median 3.5 → floor 14
    [125.0, 14.0, 14.0, 14.0]
    >>> index_levels(np.array([0.0, 0.0, 2.0])).tolist(), index_levels(np.zeros(2)).tolist()
    ([2.5, 2.5, 2.5], [1.0, 1.0])
    """
    m = np.asarray(maxima, dtype=np.float64)
    floor = GAIN_FLOOR * float(np.median(m)) if m.size else 0.0
    if floor > 0:
        return np.maximum(GAIN_MARGIN * m, floor)
    top = GAIN_MARGIN * float(m.max()) if m.size else 0.0
    return np.full(m.shape, top if top > 0 else 1.0)


def _gained_range(ctx: LoweringContext, rec: NodeCalibration, axis: str | None,
                  gains: tuple[float, ...]) -> tuple[float, tuple[float, ...]]:
    """Full scale and charging samples of a value carrying ``gains`` along ``axis``."""
    head = headroom_of(ctx)
    if axis is None:
        return rec.max_part * head, tuple(rec.part_quantiles)
    g = np.asarray(gains)
    if axis not in rec.axis_max:
        return rec.max_part * float(g.max()) * head, ()
    m = np.asarray(rec.axis_max[axis])
    # axis_quantiles are of values / m; under gains g they scale by g·m (median index).
    c = float(np.median(g * m))
    full = float((g * GAIN_MARGIN * m).max()) * head  # later stages: margin, no floor
    return full, tuple(c * q for q in rec.axis_quantiles[axis])


def lower_time_linear(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> Value:
    """Rule of motif ``time`` for ``dft``, ``linear`` and ``window`` nodes (with stage gains)."""
    (x,) = inputs
    in_type = ctx.types[ctx.graph.inputs_of(node)[0]]
    axes = dft_axes(node, op, in_type)
    out_type = ctx.types[node]
    source, code_in = time_source(ctx, node, x, motif="time", gains_ok=True)
    split = _out_split(out_type.complex)
    w = op_weights(op, axes.n_in, node=node)
    gain_axis, gains, scaled = code_in.gain_axis, code_in.gains, False
    if gain_axis == axes.axis:
        raise CompileError(f"node {node!r}: its input {x.node!r} carries stage gains along "
                           f"{gain_axis!r}, the axis it contracts; compile with "
                           "stage_gains='none'", node=node)
    n_rows = axes.n_in * max(1, N_PARTS[code_in.split])
    start = None
    if gain_axis is None:
        cols = np.linalg.norm(real_weights(w, code_in.split, split), axis=0)
        noise = code_in.scale / math.sqrt(12) * cols.reshape(axes.n_out, -1).max(axis=1)
        start = stage_gains(ctx, node, axes.out_axis, n_rows, noise)
    rec = calibration_of(ctx, node, node)
    full, samples = _gained_range(ctx, rec, gain_axis, gains)
    if start is not None:
        g, level = start
        w, gain_axis, gains, scaled = w * g[:, None], axes.out_axis, tuple(g), True
        full, samples = _gained_range(ctx, rec, gain_axis, gains)
        full = level * headroom_of(ctx)  # every index's level ℓ_r reaches the top
        ctx.builder().meta.setdefault("stage_gains", {})[node] = {
            "axis": gain_axis, "n": len(gains), "max_gain": float(g.max())}
    m = real_weights(w, code_in.split, split)
    bits = None
    if scaled and ctx.option("weight_bits") is None:
        bits = exact_weight_bits(_steps(ctx), n_rows)
    layer_in = LayerInput(source, m, axes.contract(code_in.split), axes.produce(split))
    return time_layer(ctx, node, code_in, [layer_in], shape=axes.out_shape(out_type, split),
                      split=split, full_scale=full, samples=samples, gain_axis=gain_axis,
                      gains=gains, weight_bits=bits)


def register_time(registry: LoweringRegistry) -> None:
    """Register the time-coded family: ``time`` for ``dft`` (default), ``linear``, ``window``;
    ``l1`` and ``amb`` (α-max-β-min) for ``magnitude``."""
    from compiler.lowering.magnitude import register_magnitude

    registry.register(DFT, "time", lower_time_linear, default=True)
    registry.register(Linear, "time", lower_time_linear)
    registry.register(Window, "time", lower_time_linear)
    register_magnitude(registry)
