r"""The ``resonator`` motif for ``dft``: one resonate-and-fire neuron per bin, fed sample by sample.

Streaming spectral analysis after Reeb et al. (spiking neural resonators for FMCW radar,
2025).  The ``N`` samples along the DFT axis enter one per step through a stream code
(:mod:`compiler.snn.stream`: bit-plane spikes, window folded into the per-sample level),
and every bin ``k`` is one resonator (:mod:`compiler.snn.resonator`) whose 2-D state
turns by ``θ_k = 2π f_k/N`` per step:

.. math:: z_k(N) = \sum_{n=0}^{N-1} x[n]\, a_k^{N-n} = \sum_n x[n]\, e^{-2πi f_k n/N} = X_k
          \qquad (a_k = e^{iθ_k},\ \text{option } \texttt{resonator\_decay}\ ρ:\ a_k = ρe^{iθ_k})

Each sample reaches each bin through one synapse per bit and part — ``B·P·K``
synapses per stream (``P = 2`` real, 4 complex) instead of the ``P·N × 4K`` matrix
of the S-FT.

**Output code.**  After the ``N`` input steps the state is held and read out in the
time-linear code of the S-FT (option ``resonator_readout='time'``): the four
compartments ``±Re, ±Im`` charge with bias ``b`` for ``T`` steps (option
``time_steps``) and fire once at ``t = E − p/b`` (``E = N + T``), so magnitude, CFAR and
S-FT motifs read the spikes as they read an S-FT layer's; each part is within ``b/2``
of the exact value; a value read on the host charges each bin at its own calibrated
scale.  ``'graded'`` sends the held state as one payload per compartment (one step, host
read-out only).  ``'log'`` (host read-out only) charges every bin at one shared scale
whose thresholds grow geometrically (:func:`~compiler.lowering.charging.log_schedule`:
±2.8 % of every value from 24 dB over the calibrated peak down to 120 dB under it), so a
new scene's target in a bin that held noise in the calibration frames is neither clipped
nor is the noise floor decoded to 0.  ``'auto'`` (default) is ``graded`` on targets with
graded spikes where the value goes to the host, ``log`` where it goes to the host
without them, else ``time``; ``docs/fourier.md`` compares the codes
(:mod:`compiler.lowering.resonator_readout` chooses the code and its scales).

**Fixed point** (targets with ``weight_bits``): the rotation coefficients have
:data:`~compiler.lowering.resonator_fixed.CHIP_COEF_BITS` = 12 fraction bits — the
format of Lava's bit-accurate resonate-and-fire model (``sin_decay``/``cos_decay``,
12 bits, shift 12), the only published one — chosen by
:func:`~compiler.lowering.resonator_fixed.fixed_coefficients` (``|a| ≤ 1``, least
drift); the state is scaled to about ``2^{state_bits − 2}`` at the calibrated full scale.
Every ``M``-th step the rotation uses a second, block-end coefficient so that a block's
product is exact to one rounding (*periodic renormalisation*, option
``resonator_renorm``: ``auto`` picks ``M`` by the least weight error,
:func:`~compiler.lowering.resonator_fixed.best_renorm`; ``off``; or a given ``M``): at
``N = 1024`` with 12 bits the weight-error bound falls from 0.14 to 0.007.  It needs the
neuron program to hold a second coefficient pair and count steps — an assumption about a
programmable neuron (Orchard et al. 2021: Loihi 2's neurons are microcode programs), as
is the resonator neuron itself.
The drift bound is recorded (``meta["resonator"]``); above
:data:`DRIFT_MAX` it is reported with a :class:`ResonatorDriftWarning` naming the bound
and the ways out — the compiler never widens the chip's format by itself: wider
coefficients (option ``resonator_coef_bits``, e.g. 16) are the user's claim about the
chip.  Given ``resonator_drift_max``, a layer over it is refused.  A host read-out divides
each bin's known gain ``|g_k|`` out in its decoder (the magnitude drift; the phase drift
stays, bounded).

Examples
--------
>>> from compiler.lowering import LoweringRegistry
>>> from ir.ops import DFT
>>> reg = LoweringRegistry()
>>> register_resonator(reg)
>>> reg.motifs(DFT)
['host', 'resonator']
"""

from __future__ import annotations

import warnings
from math import prod

import numpy as np

from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_common import dft_axes
from compiler.lowering.options import ResonatorOptions
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.resonator_bounds import check_decay, check_gains, check_levels
from compiler.lowering.resonator_fixed import (
    CHIP_COEF_BITS,
    Renorm,
    best_renorm,
    bin_angles,
    bin_gains,
    drift_report,
    fixed_coefficients,
    float_coefficients,
    renormalised_coefficients,
)
from compiler.lowering.resonator_readout import (
    MOTIF,
    choose_readout,
    log_readout,
    readout_scales,
)
from compiler.lowering.time_code import TimeCode, calibration_of, headroom_of, time_steps
from compiler.lowering.time_inputs import TimeInputOptions, encoder_headroom
from compiler.lowering.values import Value
from compiler.snn import N_PARTS, PART_AXIS, Decoder, Encoder, Phase
from compiler.snn.resonator import ResonatorParams
from compiler.snn.stream import BIT_AXIS, StreamCode
from ir.errors import CompileError
from ir.ops import DFT, Op
from radar.dsp import dft_matrix
from radar.windows import window_coefficients

__all__ = ["MOTIF", "lower_resonator", "register_resonator"]

#: Bits of the stream code per input part when ``stream_bits`` is not given.
DEFAULT_STREAM_BITS = 12
#: The drift bound above which a layer is reported (refused above ``resonator_drift_max``).
DRIFT_MAX = 0.01


class ResonatorDriftWarning(UserWarning):
    """A resonator layer's fixed-point drift bound is above :data:`DRIFT_MAX` (reported)."""
_COMPARTMENT = {"signed": (0, 1), "re_im_signed": (0, 1, 2, 3)}


def _bits(ctx: LoweringContext, node: str, ratio: float) -> tuple[int, int]:
    """``(B, s)``: stream bits and level weight ``2^s`` (integer targets: the full-scale
    state ``ratio·2^(B+s)`` within ``2^(state_bits−2)``; the bits in groups of ``w − 1``,
    one projection each, so every weight ``2^(b+s)`` is one mantissa ``≤ 2^(w−2)`` under
    its projection's exponent: no split synapses)."""
    fmt = ctx.target.number_format
    w_bits = fmt.weight_bits
    given = ctx.settings_of(ResonatorOptions).stream_bits
    if not w_bits:
        bits = int(given or DEFAULT_STREAM_BITS)
        if not 1 <= bits <= 30:
            raise CompileError(f"node {node!r}: stream_bits={bits} is outside 1..30", node=node)
        return bits, 0
    e_max = fmt.weight_exponent_max
    room = int(np.floor(np.log2(_state_top(ctx) / max(ratio, 1e-30))))
    top = min(w_bits - 1 + e_max, room)
    bits = int(given or min(max(DEFAULT_STREAM_BITS, room), top))  # fill the state
    if not 1 <= bits <= top:
        raise CompileError(f"node {node!r}: stream_bits={bits} is outside 1..{top} (weights "
                           f"2^b of {w_bits}-bit mantissas and exponents <= {e_max} reach "
                           f"2^{w_bits - 2 + e_max}; the {fmt.state_width}-bit state "
                           f"holds {room} bits at this gain)", node=node)
    groups = -(-bits // (w_bits - 1))
    return bits, int(np.clip(room - bits, 0, e_max - (groups - 1) * (w_bits - 1)))


def _state_top(ctx: LoweringContext) -> float:
    return 2.0 ** (ctx.target.number_format.state_width - 2)


def _frequencies(node: str, op: DFT, n: int) -> tuple[np.ndarray, int]:
    """DFT frequency ``f_k`` (whole, in bins of ``M``) of every output row, and ``M``.

    Zero padding (``n_fft = M > N``) is streaming ``M − N`` zeros: the resonators keep
    turning for ``M`` steps, so ``z = Σ_n x[n] a^{M−n}`` is the padded DFT.
    """
    m = op.n_fft or n
    if m < n:
        raise CompileError(f"node {node!r}: n_fft={m} is below the {n} samples the resonators "
                           "stream; give n_fft >= the axis size or motif 'time'", node=node)
    row = dft_matrix(max(n, 2), n_fft=max(m, 2), keep=op.keep, shift=op.shift)[:, 1]
    return np.rint(np.angle(np.conj(row)) * max(m, 2) / (2 * np.pi)), m


def lower_resonator(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> Value:
    """Rule of motif ``resonator`` for ``dft`` nodes (see the module docstring)."""
    if not isinstance(op, DFT):
        raise CompileError(f"node {node!r}: motif 'resonator' lowers 'dft' nodes only, not "
                           f"{op.op!r}", node=node)
    (x,) = inputs
    host = ctx.to_host(x)
    in_type = host.type
    axes = dft_axes(node, op, in_type)
    n, t_out = axes.n_in, time_steps(ctx)
    split_in = "re_im_signed" if in_type.complex else "signed"
    p_in = N_PARTS[split_in]
    rec_in = calibration_of(ctx, host.node, node)
    setting = ctx.settings_of(TimeInputOptions).encoder_headroom
    x_max = rec_in.max_part * headroom_of(ctx) * encoder_headroom(rec_in, setting) or 1.0
    rec = calibration_of(ctx, node, node)
    full = rec.max_part * headroom_of(ctx) or 1.0  # largest output part (value units)
    bits, shift = _bits(ctx, node, full / x_max)
    check_levels(node, bits, x_max, rec_in.max_part)
    window = window_coefficients(op.window, n) if op.window else np.ones(n)
    names = list(in_type.axes)
    i_axis = names.index(axes.axis)
    inner = prod(in_type.axes[a] for a in names[i_axis + 1:]) * p_in
    code = StreamCode(axis=axes.axis, length=n, inner=inner, bits=bits, x_max=x_max,
                      gains=tuple(float(w) for w in window))
    builder = ctx.builder()
    if builder.has_encoder(host.node):
        raise CompileError(f"node {node!r}: value {host.node!r} is already encoded in this "
                           "network by another consumer; give it one motif", node=node)
    src_shape = {(BIT_AXIS if a == axes.axis else a): (bits if a == axes.axis else size)
                 for a, size in in_type.axes.items()}
    src = builder.population(node, "in", {**src_shape, PART_AXIS: p_in}, motif=MOTIF,
                             source=True)
    builder.encoder(Encoder(port=host.node, population=src.id, split=split_in, node=host.node,
                            code=code))
    freqs, m = _frequencies(node, op, n)  # m input steps (n samples, then zeros)
    theta = bin_angles(freqs, m)
    rho = ctx.settings_of(ResonatorOptions).resonator_decay
    if not 0.0 < rho <= 1.0:
        raise CompileError(f"node {node!r}: resonator_decay={rho} is outside (0, 1]", node=node)
    integer = ctx.target.number_format.integer
    renorm = None
    if integer:
        check_decay(node, rho, ctx.settings_of(ResonatorOptions).resonator_coef_bits)
        unit = code.step_of_level / 2 ** shift  # value of one state unit
        renorm, f_bits = _coefficients(ctx, node, theta, rho, m)
        c, s = renorm.c, renorm.s
        renorm = renorm if renorm.block else None
        w_level = 2.0 ** shift
    else:
        unit, f_bits, w_level = 1.0, 0, code.step_of_level
        c, s = float_coefficients(theta, rho)
    b, scales = readout_scales(ctx, node, rec, axes.out_axis, full / unit, t_out, integer)
    drift = drift_report(c, s, theta, n_steps=m, rho=rho, bits=f_bits, full_state=full / unit,
                         renorm=renorm)
    given = ctx.settings_of(ResonatorOptions).resonator_drift_max
    limit = DRIFT_MAX if given is None else float(given)
    if drift["bound"] > limit and given is None:
        warnings.warn(
            f"node {node!r}: resonator drift bound {drift['bound']:.4f} over N={m} steps with "
            f"the chip's {f_bits}-bit rotation coefficients (weight error "
            f"{drift['weight_error']:.4f}, renormalised every {drift['renorm_steps']} steps "
            f"(0: never); gain drift {drift['gain_drift']:.4f}, divided out on a host "
            f"read-out; phase drift {drift['phase_drift_rad']:.4f} rad); "
            "resonator_renorm='auto' if it is off, fewer samples per DFT, or "
            "resonator_coef_bits=16 if the chip's neurons multiply wider (an assumption: "
            "Lava's resonate-and-fire format is 12 bits), or the S-FT (motif time)",
            ResonatorDriftWarning, stacklevel=2)
    elif drift["bound"] > limit:
        why = (f"with {f_bits}-bit coefficients; raise resonator_coef_bits"
               if drift["truncation"] <= limit else
               f"by the state's rounding ({drift['truncation']:.4f} of the full-scale state "
               f"{full / unit:.0f}); raise resonator_drift_max or calibrate on data")
        raise CompileError(f"node {node!r}: resonator drift bound {drift['bound']:.4f} over "
                           f"N={m} steps exceeds resonator_drift_max={limit} {why}", node=node)
    readout = choose_readout(ctx, node)
    graded = readout == "graded"
    log = log_readout(ctx, full / unit, t_out, integer) if readout == "log" else None
    if log is not None:  # one shared logarithmic scale: no per-bin maxima to clip at
        scales = None
        v_th = log.v_th
        charging = tuple(Phase(start_step=m + st, bias=bb, input_on=False)
                         for st, bb in zip(log.starts, log.biases, strict=True))
    else:
        v_th = b * t_out + b / 2
        charging = (Phase(start_step=m, bias=0.0 if graded else b, input_on=False,
                          spiking_on=not graded),)
    phases = (Phase(start_step=0, spiking_on=False), *charging,
              Phase(start_step=m + (1 if graded else t_out), input_on=False, spiking_on=False))
    per_bin = {} if graded or scales is None else {"scale_axis": axes.out_axis,
                                                   "scales": tuple(scales)}
    ends = ({"renorm_steps": renorm.block, "cos_end": tuple(renorm.c_end),
             "sin_end": tuple(renorm.s_end)} if renorm is not None else {})
    params = ResonatorParams(axis=axes.out_axis, cos=tuple(c), sin=tuple(s), coef_bits=f_bits,
                             v_th=v_th if not graded else 1.0, phases=phases, **per_bin, **ends)
    out_type = ctx.types[node]
    pop = builder.population(node, "out", axes.out_shape(out_type, "re_im_signed"), params,
                             motif=MOTIF)
    w_bits = ctx.target.number_format.weight_bits
    _connect(builder, node, src.id, pop.id, bits, split_in, axes.out_axis, len(freqs), w_level,
             group=(w_bits - 1) if w_bits else bits)
    builder.meta.setdefault("resonator", {})[node] = {
        **drift, "stream_bits": bits, "readout": readout, "readout_steps": 1 if graded else t_out,
        "input_steps": m, "unit": unit, "bias": b, "v_th": v_th,
        **({"log_readout": log.describe()} if log is not None else {})}
    # host read-outs divide out each bin's known fixed-point gain |g_k| (magnitude drift)
    g_mag = (np.abs(bin_gains(c, s, theta, m, rho=rho, bits=f_bits, renorm=renorm))
             if f_bits else None)
    check_gains(node, rho, f_bits, g_mag)
    if graded:
        comp = {"gain_axis": axes.out_axis, "gains": tuple(g_mag)} if f_bits else {}
        dec = Decoder(port=node, population=pop.id, kind="membrane", scale=unit / 2,
                      combine="re_im_signed", node=node, **comp)
        return ctx.spike_value(node, pop, dec, (m, m + 1), kind="graded", end=m + 1,
                               split="re_im_signed")
    if log is not None:
        comp = {"gain_axis": axes.out_axis, "gains": tuple(g_mag)} if f_bits else {}
        dec = Decoder(port=node, population=pop.id, kind="spike_table", scale=unit,
                      table=tuple(float(v) for v in log.levels()), t_ref=float(m),
                      missing=0.0, combine="re_im_signed", node=node, **comp)
        return ctx.spike_value(node, pop, dec, (m, m + t_out), kind="time-table",
                               end=m + t_out, split="re_im_signed")
    gained = ({"gain_axis": axes.out_axis,
               "gains": tuple((g_mag if f_bits else 1.0) / scales)} if per_bin else {})
    dec = Decoder(port=node, population=pop.id, kind="spike_time", scale=unit * b,
                  t_ref=float(m + t_out), missing=0.0, combine="re_im_signed", node=node,
                  **gained)
    tc = TimeCode(end=m + t_out, scale=unit * b, split="re_im_signed", **gained)
    return ctx.spike_value(node, pop, dec, (m, m + t_out), **tc.as_code())


def _coefficients(ctx: LoweringContext, node: str, theta: np.ndarray, rho: float,
                  n: int) -> tuple[Renorm, int]:
    """Fixed-point coefficients and their renormalisation (``block`` 0: none).

    Fraction bits: option ``resonator_coef_bits``, else the chip's format
    (:data:`~compiler.lowering.resonator_fixed.CHIP_COEF_BITS`), never widened here.
    Option ``resonator_renorm``: ``auto`` (default) takes the block length with the least
    weight error, or none where none helps; an integer fixes it; ``off`` never renormalises.
    """
    opts = ctx.settings_of(ResonatorOptions)
    f_bits = CHIP_COEF_BITS if opts.resonator_coef_bits is None else int(opts.resonator_coef_bits)
    mode = opts.resonator_renorm
    if mode == "off":
        c, s = fixed_coefficients(theta, rho, f_bits, n_steps=n)
        return Renorm(c, s, c, s, 0), f_bits
    if mode == "auto":
        return best_renorm(theta, rho, f_bits, n_steps=n), f_bits
    if mode > n:
        raise CompileError(f"node {node!r}: resonator_renorm={mode} is longer than the {n} "
                           f"input steps; give 2..{n}, 'auto' or 'off'", node=node)
    return renormalised_coefficients(theta, rho, f_bits, n_steps=n, block=int(mode)), f_bits


def _connect(builder, node: str, src: str, dst: str, bits: int, split_in: str, out_axis: str,
             n_bins: int, w_level: float, group: int) -> None:
    """Fan-out synapses: bit ``b`` of part ``p`` → compartment of ``p`` in every bin
    (projection ``w`` for bits ``0 … group−1``, ``w1`` for the next group, …)."""
    p_in = N_PARTS[split_in]
    comp = np.array(_COMPARTMENT[split_in])
    for g, lo in enumerate(range(0, bits, group)):
        b, p, k = (a.ravel() for a in np.meshgrid(np.arange(lo, min(bits, lo + group)),
                                                  np.arange(p_in), np.arange(n_bins),
                                                  indexing="ij"))
        builder.matrix(node, f"w{g or ''}", src, dst, contract=(BIT_AXIS, PART_AXIS),
                       produce=(out_axis, PART_AXIS), motif=MOTIF, rows=b * p_in + p,
                       cols=k * 4 + comp[p], values=w_level * 2.0 ** b,
                       n_in_out=(bits * p_in, n_bins * 4))


def register_resonator(registry: LoweringRegistry) -> None:
    """Register ``resonator`` for ``dft`` (never the default)."""
    registry.register(DFT, MOTIF, lower_resonator)
