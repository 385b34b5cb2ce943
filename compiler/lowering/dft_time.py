r"""The time-coded S-FT motif (``time``, default for ``dft``): one spike per neuron, two stages.

Values travel in the *time-linear codes* of :mod:`compiler.lowering.time_code`
(part value ``z = s·(E − t)`` for a spike at step ``t < E``, ± parts for signed and
complex values; a host value is encoded with ``E = T``, ``s = X/T``).

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

**Stage gains** (option ``stage_gains``, ``auto`` | ``none``): a layer followed
by time-coded linear stages along other axes may scale each index of its output
axis by its own gain (each range bin then spans the whole window); the decoders
divide the gains out.  The rule and its formula are in
:mod:`compiler.lowering.stage_gains`.

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

import numpy as np

from compiler.lowering.charging import (
    GUARD_MIN_RATIO,
    choose_schedule,
    with_guard,
)
from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_common import dft_axes, op_weights, real_weights
from compiler.lowering.graded import graded_layer
from compiler.lowering.layer_weights import coarsen, connect_levels, integer_target
from compiler.lowering.options import TimeDftOptions
from compiler.lowering.registry import HOST, LoweringRegistry
from compiler.lowering.stage_gains import (
    exact_weight_bits,
    gain_mechanism,
    gained_range,
    integer_weight_bits,
    pow2_gains,
    stage_gains,
)
from compiler.lowering.time_code import (
    DEFAULT_TIME_STEPS,
    LayerInput,
    TimeCode,
    calibration_of,
    headroom_of,
    time_source,
    time_steps,
)
from compiler.lowering.time_inputs import graded_readout, guard_of
from compiler.lowering.values import SpikeValue, Value
from compiler.quantize_weights import weight_bits_of
from compiler.snn import (
    N_PARTS,
    Decoder,
    NeuronParams,
    PartLayout,
    Phase,
    Population,
)
from ir.errors import CompileError
from ir.ops import DFT, Linear, Op, Window

__all__ = ["DEFAULT_TIME_STEPS", "TimeCode", "LayerInput", "calibration_of", "headroom_of",
           "integer_target", "layer_weight_bits",
           "time_source", "time_layer", "lower_time_linear", "register_time"]

def _allow_companding(ctx: LoweringContext, node: str) -> bool:
    """Companding only where every consumer takes the value on the host."""
    return all(ctx.motif_for(c) == HOST for c in ctx.graph.consumers_of(node))


def time_layer(ctx: LoweringContext, node: str, code_in: TimeCode, inputs: list[LayerInput], *,
               shape: dict[str, int], split: PartLayout, full_scale: float,
               samples: tuple[float, ...] = (), motif: str = "time",
               gain_axis: str | None = None, gains: tuple[float, ...] = (),
               weight_bits: int | None = None, neuron_gains: bool = False) -> SpikeValue:
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
        Width to quantize to (default: option ``weight_bits``, else the target's, else 24).
    neuron_gains : bool
        The ``gains`` are per-neuron scales of the charging stage, not in the matrices:
        ``full_scale`` and ``samples`` are those of the *most* gained index (the level
        over ``max g``) and index ``r`` gets the threshold/bias scale ``c_r = max g / g_r``,
        so its spikes carry ``g_r`` times its value like a gained column would.

    Returns
    -------
    SpikeValue
        Time-linear code for the constant schedule, ``time-table`` for companding.
    """
    t = time_steps(ctx)
    bits = weight_bits or layer_weight_bits(ctx, node)
    stacked = np.concatenate([i.matrix.ravel() for i in inputs])
    whole = integer_target(ctx) and (ctx.target.number_format.bias_mantissa_bits or True)
    top = float(max(gains)) if neuron_gains else 1.0
    if graded_readout(ctx, node, host_only=_allow_companding(ctx, node),
                      neuron_gains=neuron_gains and top > 1):
        return graded_layer(ctx, node, code_in, inputs, shape=shape, split=split,
                            full_scale=full_scale, motif=motif, gain_axis=gain_axis,
                            gains=gains, bits=bits, whole=bool(whole))
    mode = ctx.settings_of(TimeDftOptions).charging
    n_guard, guard = 0, 1.0
    if mode != "constant" and not _allow_companding(ctx, node):
        mode = "constant"
    elif mode != "constant":
        n_guard, guard = guard_of(ctx, node, t)
    guard0 = guard

    def fit(unit: float) -> tuple[float, tuple]:
        nonlocal guard
        sched, errors = choose_schedule(t - n_guard, (full_scale or 1.0) / unit,
                                        np.asarray(samples) / unit if samples else None,
                                        mode=mode, whole=whole)
        guarded = with_guard(sched, n_guard, guard, whole)
        while _excess(ctx, guarded, top) > 1.0 and guard / 2 >= min(GUARD_MIN_RATIO, guard0):
            guard /= 2  # a smaller guard before coarser weights: the state must hold its top
            guarded = with_guard(sched, n_guard, guard, whole)
        return _excess(ctx, guarded, top), (guarded, errors, guard)

    fitted = coarsen(node, inputs, stacked, code_in, bits, bool(whole), fit, memo=ctx.memo)
    levels, rounding, unit, bits = fitted.levels, fitted.rounding, fitted.unit, fitted.bits
    sched, errors, guard = fitted.fitted
    e_in, e_out = code_in.end, code_in.end + t
    phases = (Phase(start_step=0, spiking_on=False),
              *(Phase(start_step=e_in + s, bias=b, input_on=False)
                for s, b in zip(sched.starts, sched.biases, strict=True)),
              Phase(start_step=e_out, input_on=False, spiking_on=False))
    scales = {}
    g_top = 1.0
    if neuron_gains and max(gains) > 1:
        g_top = float(max(gains))
        scales = {"scale_axis": gain_axis, "scales": tuple(g_top / g for g in gains)}
    params = NeuronParams(du=0.0, dv=0.0, v_th=sched.v_th, reset="fire_once", phases=phases,
                          **scales)
    builder = ctx.builder()
    pop: Population = builder.population(node, "out", shape, params, motif=motif)
    connect_levels(builder, node, pop.id, inputs, levels, motif)
    charging = {**sched.describe(), "mse": errors, "weight_bits": bits, "unit": unit,
                "rounding": rounding, "guard": {"ratio": guard, "steps": n_guard},
                **({"neuron_gains": {"axis": gain_axis, "max_scale": g_top}} if scales else {})}
    builder.meta.setdefault("charging", {})[node] = charging
    gained = {"gain_axis": gain_axis, "gains": tuple(gains)} if gain_axis else {}
    if sched.kind == "constant":
        b = sched.biases[0]
        dec = Decoder(port=node, population=pop.id, kind="spike_time", scale=unit * b * g_top,
                      t_ref=float(e_out), missing=0.0, combine=split, node=node, **gained)
        code = TimeCode(end=e_out, scale=unit * b * g_top, split=split, **gained).as_code()
    else:
        dec = Decoder(port=node, population=pop.id, kind="spike_table", scale=unit * g_top,
                      table=tuple(float(v) for v in sched.levels()), t_ref=float(e_in),
                      missing=0.0, combine=split, node=node, **gained)
        code = {"kind": "time-table", "end": e_out, "split": split}
    return ctx.spike_value(node, pop, dec, (e_in, e_out), **code, charging=charging)


def layer_weight_bits(ctx: LoweringContext, node: str) -> int:
    """Weight width of a time layer: option ``weight_bits``, else the target's, else exact.

    Lowering at the target's width keeps the quantize pass from re-scaling the layer
    (its thresholds and biases stay the whole numbers the schedule chose).
    """
    return weight_bits_of(integer_weight_bits(ctx), node=node)


def _excess(ctx: LoweringContext, sched, top: float) -> float:
    """How far the schedule's threshold and largest bias (times the largest per-neuron
    scale ``top``) exceed the target's ranges (≤ 1: they fit)."""
    fmt = ctx.target.number_format
    out = 1.0
    limit = fmt.threshold_max
    if limit:
        out = max(out, sched.v_th * top / limit)
    b_max = fmt.bias_max
    if b_max:
        out = max(out, max(sched.biases) * top / b_max)
    return out


def _host_moment(ctx: LoweringContext, value: Value, axis: str) -> np.ndarray | None:
    """The calibrated second moment of a host-encoded input along ``axis`` (None: none)."""
    if isinstance(value, SpikeValue) and value.network == ctx.network_index:
        return None  # read as spikes: its code carries gains the moment does not know
    rec = ctx.calibration.get(value.node)
    return None if rec is None else getattr(rec, "second_moments", {}).get(axis)


def _out_split(complex_out: bool) -> PartLayout:
    return "re_im_signed" if complex_out else "signed"


def _real_weights(ctx: LoweringContext, w: np.ndarray, in_split: str, out_split: str
                  ) -> np.ndarray:
    """:func:`~compiler.lowering.dft_common.real_weights`, once per measured compile for
    equal arguments (``ctx.memo``)."""
    if ctx.memo is None:
        return real_weights(w, in_split, out_split)
    return ctx.memo.of_arrays("real_weights", (np.asarray(w),), (in_split, out_split),
                              lambda: real_weights(w, in_split, out_split))


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
    neurons = gain_mechanism(ctx) == "neurons"
    if gain_axis is None:
        m0 = _real_weights(ctx, w, code_in.split, split)
        cols = np.linalg.norm(m0, axis=0)
        noise = code_in.scale / math.sqrt(12) * cols.reshape(axes.n_out, -1).max(axis=1)
        peak = float(np.abs(m0).max(initial=0.0))
        unit = (peak / (2 ** (layer_weight_bits(ctx, node) - 1) - 1) * code_in.scale
                if neurons and peak > 0 else None)
        start = stage_gains(ctx, node, axes.out_axis, n_rows, t_steps=time_steps(ctx),
                            stage_rule=lower_time_linear, code_noise=noise, neuron_unit=unit)
    rec = calibration_of(ctx, node, node)
    full, samples = gained_range(rec, gain_axis, gains, headroom_of(ctx))
    if start is not None:
        g, level = start
        if neurons:  # per-neuron threshold/bias scales: powers of two, weights untouched
            g = pow2_gains(g)
        else:
            w, scaled = w * g[:, None], True
        gain_axis, gains = axes.out_axis, tuple(g)
        full, samples = gained_range(rec, gain_axis, gains, headroom_of(ctx))
        full = level * headroom_of(ctx)  # every index's level ℓ_r reaches the top
        ctx.builder().meta.setdefault("stage_gains", {})[node] = {
            "axis": gain_axis, "n": len(gains), "max_gain": float(g.max()),
            "mechanism": "neurons" if neurons else "weights"}
        if neurons:
            top = float(g.max())
            full, samples = full / top, tuple(x / top for x in samples)
    m = _real_weights(ctx, w, code_in.split, split)
    bits = None
    if scaled and ctx.settings_of(TimeDftOptions).weight_bits is None:
        bits = exact_weight_bits(time_steps(ctx), n_rows)
    layer_in = LayerInput(source, m, axes.contract(code_in.split), axes.produce(split),
                          _host_moment(ctx, x, axes.axis))
    return time_layer(ctx, node, code_in, [layer_in], shape=axes.out_shape(out_type, split),
                      split=split, full_scale=full, samples=samples, gain_axis=gain_axis,
                      gains=gains, weight_bits=bits,
                      neuron_gains=neurons and start is not None)


def register_time(registry: LoweringRegistry) -> None:
    """Register the time-coded family: ``time`` for ``dft`` (default), ``linear``, ``window``;
    ``l1`` and ``amb`` (α-max-β-min) for ``magnitude``."""
    # cycle: compiler.lowering.magnitude imports time_layer from this module at its top
    from compiler.lowering.magnitude import register_magnitude

    registry.register(DFT, "time", lower_time_linear, default=True)
    registry.register(Linear, "time", lower_time_linear)
    registry.register(Window, "time", lower_time_linear)
    register_magnitude(registry)
