r"""The ``time-fft`` motif of ``dft``: a time-coded radix-4 (mixed-radix) spiking FFT.

**Factorisation.** With :math:`N = r_0 r_1 \cdots r_{L-1}` (:func:`radix_plan`:
radix 4 first, then one radix 2 if :math:`\log_2 N` is odd, then any other prime
factors), decimation in frequency writes the DFT as :math:`F = P\,A_{L-1}\cdots A_0`,

.. math:: A_\ell = D_\ell \,(I_{a_\ell} \otimes F_{r_\ell} \otimes I_{b_\ell}), \qquad
          (D_\ell)_{o} = \omega_{r_\ell b_\ell}^{\,n_2 k_1}

(:func:`fft_stages`): ``a`` sub-transforms of length :math:`r b`, each split into
``r`` sub-transforms of length ``b`` by an ``r``-point butterfly over inputs
``b`` apart and a twiddle; ``P`` is the mixed-radix digit reversal.  Every output
reads ``r`` inputs, so a layer of ``2N`` real neurons (Re, Im) has at most
``2r·2N`` = ``16N`` synapses for radix 4 (fewer: the ±1/±i butterfly entries of
untwiddled outputs have one real synapse, not two).  A node's window multiplies
``A_0``'s columns, zero padding drops them, and ``P`` with ``keep``/``shift``
selects and orders ``A_{L-1}``'s rows (:func:`op_stages`): the digit reversal is
in the wiring and the last layer is in the IR's bin order.

**Timing.** Layer ℓ is a population of ramp neurons (``du = dv = 0``, fire once)
with a silent stage ``[ℓT, (ℓ+1)T)`` (input on, no spiking) and a charging stage
``[(ℓ+1)T, (ℓ+2)T)`` (input off, bias :math:`b_\ell`); ``(L+1)·T`` steps in all.
Every layer's input uses one code: value ``z`` ↔ spike step
:math:`t = t_0 + T/2 - z/s` in its window ``[t_0, t_0+T)`` (``s`` = value per step,
bound :math:`B = sT/2`; no spike = :math:`-B`).  The silent stage then ends with
:math:`V = \sum_j w_j (T/2 + z_j/s_\ell) + V_{clk}`, and one *clock* neuron per
repetition, spiking at step 0 into layer ℓ with delay ℓT and weight
:math:`-\tfrac12\sum_j w_j` (only on rows whose weights do not sum to zero: the
butterflies' k₁ = 0 outputs), cancels the offset: :math:`V = (Wz)/s_\ell`.  With
:math:`b_\ell = s_{\ell+1}/s_\ell` and :math:`v_{th} = b_\ell (T+1)/2` the neuron
fires at :math:`t_0' + T/2 - \mathrm{round}(V/b_\ell)`, i.e. it emits
:math:`Wz` in the next window's code, rounded to a step (half up).

**Exactness.** Weights are rounded to multiples of :data:`WEIGHT_QUANTUM` and
:math:`b_\ell` to 8 significant bits (rounded up), so thresholds, biases and
every membrane sum are dyadic and exact: the closed-form and step engines give
identical spikes.

**Bounds.** ``B_0`` is the input range ``X`` and ``B_L`` the output bound ``Y``
(calibrated × option ``headroom``, else ``X`` times the weights' worst case); the layers
between take the geometric interpolation :math:`X (Y/X)^{\ell/L}` (exact growth
for a tone), times :data:`STAGE_HEADROOM`, capped by the worst case.

Examples
--------
>>> radix_plan(512), radix_plan(64), radix_plan(24)
((4, 4, 4, 4, 2), (4, 4, 4), (4, 2, 3))
>>> r = sfft_resources(512, 100)
>>> r.neurons, r.synapses, r.steps
(4608, 37888, 550)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from compiler.lowering.context import LoweringContext
from compiler.lowering.dft_common import PART_IN, PART_OUT, dft_axes
from compiler.lowering.dft_rate import calibrated_bound, normalize_axes_of
from compiler.lowering.options import FftOptions
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.values import SpikeValue, Value
from compiler.snn import PART_AXIS, Decoder, LatencyCode, NeuronParams, Phase
from ir.errors import CompileError
from ir.ops import DFT, Op
from radar.dsp import dft_bins
from radar.windows import window_coefficients

__all__ = [
    "MOTIF", "DEFAULT_STEPS", "WEIGHT_QUANTUM", "STAGE_HEADROOM",
    "SfftResources", "sfft_resources", "radix_plan", "fft_stages", "op_stages",
    "register_fft", "lower_fft",
]

MOTIF = "time-fft"
#: Time steps ``T`` per layer when the option ``time_steps`` is not given.
DEFAULT_STEPS = FftOptions().time_steps  # declared in compiler.lowering.options
#: Weights are rounded to multiples of this (dyadic) quantum.
WEIGHT_QUANTUM = 2.0 ** -24
#: Factor on the interpolated bounds of the layers between input and output.
STAGE_HEADROOM = 1.0


@dataclass(frozen=True)
class SfftResources:
    """The S-FFT's analytic cost (Vogginger et al. 2022, Table 3): ``L = log4 N`` layers.

    Attributes
    ----------
    n_layers : float
        :math:`L = \\log_4 N` (fractional when N is not a power of 4).
    neurons, synapses, steps : int
        :math:`2NL`, :math:`2N(8L + 1)`, :math:`(L + 1)T`.
    """

    n: int
    t_steps: int
    n_layers: float
    neurons: int
    synapses: int
    steps: int


def sfft_resources(n: int, t_steps: int) -> SfftResources:
    r"""Analytic resources of an ``n``-point radix-4 S-FFT with ``t_steps`` steps per layer.

    .. math:: L = \log_4 N, \quad \text{neurons} = 2NL, \quad
              \text{synapses} = 2N(8L + 1), \quad \text{steps} = (L + 1)T

    Parameters
    ----------
    n : int
        Transform length (a power of 2).
    t_steps : int
        Steps per layer ``T``.

    Returns
    -------
    SfftResources

    Raises
    ------
    CompileError
        If ``n`` is not a power of 2 >= 2 or ``t_steps < 1``.

    Examples
    --------
    >>> r = sfft_resources(256, 100)
    >>> r.n_layers, r.neurons, r.synapses, r.steps
    (4.0, 2048, 16896, 500)

    Notes
    -----
    Vogginger et al.'s Table 3 row (512 inputs, 4 608 neurons, 37 888 synapses, 550 steps)
    is this formula at ``N = 512, T = 100``, ``L = 4.5``.  The compiled network has
    ``ceil`` layers (a radix-2 layer counts as a whole layer of ``2N`` neurons), stores
    only non-zero synapses (at most ``16N`` per layer) and adds the clock neurons and
    offset synapses; :func:`lower_fft` records both counts.
    """
    if n < 2 or n & (n - 1) or t_steps < 1:
        raise CompileError(f"sfft_resources: need n a power of 2 >= 2 and t_steps >= 1, got "
                           f"n={n}, t_steps={t_steps}")
    layers = float(np.log2(n) / 2)
    return SfftResources(n=n, t_steps=t_steps, n_layers=layers, neurons=round(2 * n * layers),
                         synapses=round(2 * n * (8 * layers + 1)),
                         steps=round((layers + 1) * t_steps))


def radix_plan(n: int) -> tuple[int, ...]:
    """The radices of an ``n``-point FFT: 4s, then a 2 if needed, then other primes ascending.

    Examples
    --------
    >>> radix_plan(8), radix_plan(1)
    ((4, 2), ())
    """
    out, m = [], int(n)
    while m % 4 == 0:
        out, m = out + [4], m // 4
    if m % 2 == 0:
        out, m = out + [2], m // 2
    p = 3
    while m > 1:
        while m % p == 0:
            out, m = out + [p], m // p
        p += 2
    return tuple(out)


def fft_stages(n: int, radices: tuple[int, ...] | None = None
              ) -> tuple[list[sp.csr_matrix], np.ndarray]:
    """The DIF stage matrices ``A_ℓ`` (``n × n``, complex CSR) and the output bins.

    Returns ``(stages, bins)`` with ``(A_{L-1} ⋯ A_0 x)[p] = DFT(x)[bins[p]]``, for
    ``radices`` (default :func:`radix_plan`; ``(n,)`` is the dense DFT in one stage).

    Raises
    ------
    CompileError
        If the radices do not multiply to ``n``.

    Examples
    --------
    >>> stages, bins = fft_stages(8)
    >>> prod = stages[1] @ stages[0]
    >>> bool(np.allclose(prod.toarray(), np.fft.fft(np.eye(8))[bins]))
    True
    >>> bins.tolist()
    [0, 4, 1, 5, 2, 6, 3, 7]
    """
    radices = radix_plan(n) if radices is None else tuple(int(r) for r in radices)
    if int(np.prod(radices)) != n or min(radices, default=2) < 2:
        raise CompileError(f"fft_radices={list(radices)} must be integers >= 2 whose product "
                           f"is the transform size {n}")
    stages, size, bins = [], n, np.zeros(1, np.int64)
    for r in radices:
        b = size // r
        j, k1, n1, n2 = np.meshgrid(np.arange(n // size), np.arange(r), np.arange(r),
                                    np.arange(b), indexing="ij")
        rows = (j * size + k1 * b + n2).ravel()
        cols = (j * size + n1 * b + n2).ravel()
        phase = ((n2 * k1) % size) * (1.0 / size) + ((n1 * k1) % r) * (1.0 / r)
        coef = np.exp(-2j * np.pi * phase).ravel()
        stages.append(sp.csr_matrix((coef, (rows, cols)), shape=(n, n)))
        bins = (bins[:, None] + (n // size) * np.arange(r)[None, :]).ravel()  # k = k1·stride + ...
        size = b
    return stages, bins if stages else np.zeros(1, np.int64)


def op_stages(op: DFT, n_in: int, radices: tuple[int, ...] | None = None
             ) -> list[sp.csr_matrix]:
    """The stages of one ``dft`` node: window and zero padding in ``A_0``, bins in ``A_{L-1}``.

    The product equals :func:`compiler.lowering.dft_common.op_weights` (``n_out × n_in``).

    Examples
    --------
    >>> from compiler.lowering.dft_common import op_weights
    >>> op = DFT(axis="s", n_fft=16, keep="positive", window="hann")
    >>> a = op_stages(op, 12)
    >>> [m.shape for m in a]
    [(16, 12), (8, 16)]
    >>> bool(np.allclose((a[1] @ a[0]).toarray(), op_weights(op, 12)))
    True
    """
    n = op.n_points(n_in)
    stages, bins = fft_stages(n, radices)
    scale = np.ones(n_in) if op.window is None else window_coefficients(op.window, n_in)
    stages[0] = (stages[0][:, :n_in] @ sp.diags(scale)).tocsr()
    position = np.empty(n, np.int64)
    position[bins] = np.arange(n)
    stages[-1] = stages[-1][position[dft_bins(n, keep=op.keep, shift=op.shift)]].tocsr()
    return stages


def _real_coo(a: sp.csr_matrix, in_split: str) -> tuple[np.ndarray, ...]:
    """``Re(d_q·A_ol·c_p)`` at rows ``(l, p)``, cols ``(o, q)`` (re_im out), quantized, no zeros."""
    coo = a.tocoo()
    c, d = np.asarray(PART_IN[in_split]), np.asarray(PART_OUT["re_im"])
    vals = np.real(coo.data[:, None, None] * c[None, :, None] * d[None, None, :])
    vals = np.round(vals / WEIGHT_QUANTUM) * WEIGHT_QUANTUM
    rows = (coo.col[:, None, None] * c.size + np.arange(c.size)[None, :, None])
    cols = (coo.row[:, None, None] * d.size + np.arange(d.size)[None, None, :])
    rows, cols = np.broadcast_to(rows, vals.shape), np.broadcast_to(cols, vals.shape)
    live = vals != 0
    n_rows, n_cols = a.shape[1] * c.size, a.shape[0] * d.size
    return rows[live], cols[live], vals[live], (n_rows, n_cols)


def _dyadic_up(x: float) -> float:
    """``x`` rounded up to 8 significant bits."""
    e = np.floor(np.log2(x)) - 7
    return float(np.ceil(x / 2.0 ** e) * 2.0 ** e)


def register_fft(registry: LoweringRegistry) -> None:
    """Register :func:`lower_fft` as motif ``time-fft`` of ``dft`` (not the default).

    Examples
    --------
    >>> reg = LoweringRegistry()
    >>> register_fft(reg)
    >>> reg.motifs(DFT)
    ['host', 'time-fft']
    """
    registry.register(DFT, MOTIF, lower_fft)


def lower_fft(ctx: LoweringContext, node: str, op: Op, inputs: list[Value]) -> SpikeValue:
    """Lower one ``dft`` node to the L-layer time-coded S-FFT of the module docstring.

    Parameters
    ----------
    ctx : LoweringContext
        Options read: ``time_steps`` (``T`` per layer, even; default :data:`DEFAULT_STEPS`),
        ``input_range`` (input bound without calibration, default 1.0), ``fft_radices``
        (override of :func:`radix_plan`, e.g. ``[N]``: the dense S-FT in this code).
    node : str
        The node id.
    op : DFT
        Its op.
    inputs : list of Value
        The input value (a spike value is decoded to the host first).

    Returns
    -------
    SpikeValue
        Population ``<node>/out`` (output axes + ``part`` (Re, Im)), a ``spike_time``
        decoder, window ``(L·T, (L+1)·T)``, code ``{"kind": "latency", "t_mid", "scale",
        "bound", "layers"}`` (value = ``scale·(t_mid − t)``).

    Raises
    ------
    CompileError
        For an odd or too small ``time_steps``, or an op that is not ``dft``.
    """
    (value,) = inputs
    if not isinstance(op, DFT):
        raise CompileError(f"node {node!r}: motif {MOTIF!r} lowers 'dft' only, got {op.op!r}",
                           node=node)
    steps = ctx.settings_of(FftOptions).time_steps
    if steps < 2 or steps % 2:
        raise CompileError(f"node {node!r} ({MOTIF}): time_steps={steps} must be even and >= 2 "
                           f"(the code's zero sits at T/2); use {steps + 1}", node=node)
    in_type = ctx.types[value.node]
    axes = dft_axes(node, op, in_type)
    radices = ctx.settings_of(FftOptions).fft_radices
    try:
        stages = op_stages(op, axes.n_in, None if radices is None else tuple(radices))
    except CompileError as err:  # the option's radices: name the node
        raise CompileError(f"node {node!r} ({MOTIF}): {err}", node=node) from None
    split = "re_im" if in_type.complex else "none"
    found = calibrated_bound(ctx, value.node)
    x_bound = found if found else ctx.settings_of(FftOptions).input_range
    code = LatencyCode(t_min=0, t_max=steps, x_min=-x_bound, x_max=x_bound)
    source = ctx.encode(value, consumer=node, code=code, split=split, motif=MOTIF,
                        normalize_axes=normalize_axes_of(ctx, value.node))
    real = [_real_coo(a, split if i == 0 else "re_im") for i, a in enumerate(stages)]
    bounds = _bounds(ctx, node, real, split, x_bound)
    b = ctx.builder()
    clock = b.population(node, "clock", {**axes.repeat, "clock": 1},
                         NeuronParams(du=1.0, v_th=1.0, reset="fire_once",
                                      phases=(Phase(start_step=0, bias=1.0),)), motif=MOTIF)
    scale, src, src_axes = 2 * x_bound / steps, source.id, axes.contract(split)
    n_layers = len(stages)
    for i, (rows, cols, vals, n_in_out) in enumerate(real):
        gain = _dyadic_up(bounds[i + 1] / (scale * steps / 2))
        last = i == n_layers - 1
        shape = dict(ctx.types[node].axes) if last else {
            (f"{node}_fft" if a == axes.axis else a): (stages[i].shape[0] if a == axes.axis
                                                      else n) for a, n in in_type.axes.items()}
        out_axis = axes.out_axis if last else f"{node}_fft"
        shape[PART_AXIS] = 2
        t0 = i * steps
        phases = ((Phase(start_step=0, input_on=False, spiking_on=False),) if i else ()) + (
            Phase(start_step=t0, spiking_on=False),
            Phase(start_step=t0 + steps, bias=gain, input_on=False),
            Phase(start_step=t0 + 2 * steps, input_on=False, spiking_on=False))
        params = NeuronParams(du=0.0, dv=0.0, v_th=gain * (steps + 1) / 2, reset="fire_once",
                              phases=phases)
        pop = b.population(node, "out" if last else f"layer{i}", shape, params, motif=MOTIF)
        b.matrix(node, f"w{i}", src, pop.id, contract=src_axes, produce=(out_axis, PART_AXIS),
                 rows=rows, cols=cols, values=vals, n_in_out=n_in_out, motif=MOTIF)
        offset = -0.5 * np.bincount(cols, weights=vals, minlength=n_in_out[1])
        live = np.flatnonzero(offset)
        b.matrix(node, f"clock{i}", clock.id, pop.id, contract=("clock",),
                 produce=(out_axis, PART_AXIS), rows=np.zeros(live.size, np.int64), cols=live,
                 values=offset[live], n_in_out=(1, n_in_out[1]),
                 delays=np.full(live.size, t0, np.int64), motif=MOTIF)
        src, src_axes, scale = pop.id, (out_axis, PART_AXIS), scale * gain
    t_mid = n_layers * steps + steps // 2
    bound = scale * steps / 2
    decoder = Decoder(port=node, population=pop.id, kind="spike_time", scale=scale,
                      t_ref=float(t_mid), missing=-bound, combine="re_im", node=node)
    return ctx.spike_value(node, pop, decoder, (n_layers * steps, (n_layers + 1) * steps),
                           kind="latency", t_mid=t_mid, scale=scale, bound=bound,
                           layers=n_layers,
                           calibrated=found is not None)


def _bounds(ctx: LoweringContext, node: str, real: list, split: str,
            x_bound: float) -> list[float]:
    """``B_0 … B_L``: input range, interpolated layer bounds, output bound (module docstring)."""
    worst = [x_bound]
    for _rows, cols, vals, (_n_rows, n_cols) in real:
        # inputs of one value share a bound, so the worst |Re|/|Im| is the row-L1 norm
        worst.append(worst[-1] * float(np.bincount(cols, np.abs(vals), n_cols).max()))
    found = calibrated_bound(ctx, node)
    n_layers = len(real)
    y = min(found, worst[-1]) if found else worst[-1]
    inner = [min(worst[i], STAGE_HEADROOM * x_bound * (y / x_bound) ** (i / n_layers))
             for i in range(1, n_layers)]
    return [x_bound, *inner, y]
