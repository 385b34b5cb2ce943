r"""Per-index stage gains of the time-coded S-FT (option ``stage_gains``, ``auto`` | ``none``).

One full scale per layer wastes the window on weak bins: with the Tx→Rx leakage
at range 0 ~60 dB over the targets, a target's range bin decodes to 0.  When the
next stage is linear along *another* axis (Doppler DFT along ``chirp`` after the
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
``dft``/``linear``/``window`` stages along other axes and then to the host only —
except on the moving part of a static split (:mod:`compiler.passes.static_split`):
the stationary levels the gains exploit (leakage, static clutter) are then on the
host, and what is left (targets, noise) moves between range bins from scene to
scene, so calibrated per-bin levels would saturate a new target (measured on the two
OpenRadar captures, each calibrated on the other, loihi2: cell precision 0.88–0.91
with gains, 0.97–0.98 without; the preset scenes are unchanged, 0.99 / 0.99).

The rule of those stages (:func:`compiler.lowering.dft_time.lower_time_linear`)
calls :func:`stage_gains` and :func:`gained_range`; it passes itself as
``stage_rule`` so the path search recognises the stages it lowers.

Examples
--------
>>> import numpy as np
>>> index_levels(np.array([8.0, 1.0, 1.0])).tolist()  # median 1 → floor 4
[10.0, 4.0, 4.0]
"""

from __future__ import annotations

import math

import numpy as np

from compiler.calibration import NodeCalibration
from compiler.lowering.context import LoweringContext
from compiler.lowering.options import TimeDftOptions
from compiler.lowering.registry import HOST, LoweringRule
from ir.errors import CompileError

__all__ = ["STAGE_GAINS", "GAIN_MARGIN", "GAIN_FLOOR", "GAIN_CODE_SIGMAS", "NEURON_MIN_BIAS",
           "exact_weight_bits", "gain_mechanism", "integer_weight_bits", "pow2_gains",
           "index_levels", "stage_gains",
           "gained_range"]

#: Values of the ``stage_gains`` option (the first is the default): ``auto`` picks the
#: mechanism from the target (:func:`gain_mechanism`), ``weights`` scales the weight columns,
#: ``neurons`` gives each output index its own threshold and bias scale, ``none`` is off.
STAGE_GAINS = ("auto", "none", "weights", "neurons")
#: Neuron gains: the smallest charging bias (membrane units) the weakest-gain index keeps,
#: so ``v_th = b·(T + 1/2)`` stays a whole number and the slope error of a rounded bias small.
NEURON_MIN_BIAS = 16.0
#: Stage gains: level of an index over its calibrated maximum (frame-to-frame margin).
GAIN_MARGIN = 1.25
#: Stage gains: floor of the per-index levels, in medians of the per-index maxima.
GAIN_FLOOR = 4.0
#: Stage gains: floor of the per-index levels, in rms errors of the input code's rounding.
GAIN_CODE_SIGMAS = 5.0


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


def integer_weight_bits(ctx: LoweringContext) -> int | None:
    """The integer weight width the layers are lowered for: option ``weight_bits``, else the
    target's (None: exact weights).  The one place the option is read.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from compiler.hardware import load_profile
    >>> integer_weight_bits(SimpleNamespace(settings_of=lambda model: model(),
    ...                                     target=load_profile("loihi")))
    8
    """
    return ctx.settings_of(TimeDftOptions).weight_bits or ctx.target.number_format.weight_bits


def gain_mechanism(ctx: LoweringContext) -> str | None:
    r"""How stage gains are applied: ``"weights"``, ``"neurons"`` or None (off).

    ``auto`` gives *neuron* gains on a target with integer weights (its ``weight_bits``
    or the ``weight_bits`` option): the weights keep one scale and each output index
    ``r`` gets the per-neuron scale ``c_r = g_max / g_r`` of its threshold and charging
    bias (:attr:`compiler.snn.NeuronParams.scales`).  A neuron with scale ``c`` fires when
    ``V/c + B(k) ≥ v_th``, so index ``r`` reads its membrane with the resolution
    ``ℓ_r / T`` of its own level ``ℓ_r`` — what weight gains ``g_r`` give — without
    weight bits or membrane range spent on the gain (a gained weight column would also
    multiply the silent stage's intermediate sums by ``g_r``, beyond a 24-bit state).
    Gains are powers of two (a per-neuron bias exponent and threshold shift on a chip).
    Without a target width (exact weights) ``auto`` scales the weight columns.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from compiler.hardware import load_profile
    >>> ctx = SimpleNamespace(settings_of=lambda model: model(stage_gains="auto"),
    ...                       target=load_profile("loihi"))
    >>> gain_mechanism(ctx)
    'neurons'
    """
    mode = ctx.settings_of(TimeDftOptions).stage_gains
    if mode == "none":
        return None
    if mode in ("weights", "neurons"):
        return mode
    if not integer_weight_bits(ctx):
        return "weights"
    return "neurons" if ctx.target.number_format.per_neuron_scales else "weights"


def _gain_path(ctx: LoweringContext, node: str, axis: str,
               stage_rule: LoweringRule) -> list[str] | None:
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
        if ctx.registry.rule(type(op), motif, node=nxt) is not stage_rule or op.axis == axis:
            return None
        path.append(nxt)


def stage_gains(ctx: LoweringContext, node: str, axis: str, n_rows: int, *, t_steps: int,
                stage_rule: LoweringRule, code_noise: np.ndarray | None = None,
                neuron_unit: float | None = None) -> tuple[np.ndarray, float] | None:
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
    t_steps : int
        The charging (and encoding) window ``T``.
    stage_rule : LoweringRule
        The rule of the time-coded linear stages: a later node continues the
        path only if the registry lowers it with this rule.
    code_noise : ndarray, optional
        Per index, the rms error the input code's rounding leaves on the stage's
        output (``s_in/√12 · ‖M_col‖₂``, largest part); the levels are at least
        :data:`GAIN_CODE_SIGMAS` times it, since calibration (in floats) does not see it.
    neuron_unit : float, optional
        With neuron gains: the layer's membrane unit (value units); the largest gain
        keeps the weakest index's charging bias at :data:`NEURON_MIN_BIAS` units or more.

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

    Examples
    --------
    End to end in ``tests/test_stage_gains.py``; the levels are :func:`index_levels`.
    """
    mode = ctx.settings_of(TimeDftOptions).stage_gains
    if mode not in STAGE_GAINS:
        raise CompileError(f"node {node!r}: stage_gains={mode!r} is not a mode; use one of "
                           f"{', '.join(STAGE_GAINS)}", node=node)
    mechanism = gain_mechanism(ctx)
    if mode == "auto" and node in getattr(ctx, "moving", ()):
        return None  # static part on the host: nothing stationary left for per-bin levels
    path = _gain_path(ctx, node, axis, stage_rule) if mechanism else None
    records = [ctx.calibration.get(n) for n in path or ()]
    if not path or any(r is None or axis not in r.axis_max for r in records):
        return None
    maxima = np.asarray(records[0].axis_max[axis])
    levels = index_levels(maxima)
    if code_noise is not None:
        levels = np.maximum(levels, GAIN_CODE_SIGMAS * np.asarray(code_noise))
    if maxima.max() > 0:  # never coarser than one full scale for all (no gains)
        levels = np.minimum(levels, maxima.max())
    if mechanism == "neurons":
        if neuron_unit is None:
            return None
        ratio = levels.max() / (neuron_unit * t_steps * NEURON_MIN_BIAS)
    else:
        bits = integer_weight_bits(ctx) or exact_weight_bits(t_steps, n_rows)
        ratio = 2.0 ** (bits - 1 - (math.ceil(math.log2(t_steps)) + 2))
    if ratio < 2:
        return None
    levels = np.maximum(levels, levels.max() / ratio)
    return levels.max() / levels, float(levels.max())


def pow2_gains(gains: np.ndarray) -> np.ndarray:
    """Gains rounded down to powers of two (so no index is gained above the top level).

    Examples
    --------
    >>> pow2_gains(np.array([1.0, 3.9, 4.0, 1000.0])).tolist()
    [1.0, 2.0, 4.0, 512.0]
    """
    return np.exp2(np.floor(np.log2(np.maximum(np.asarray(gains, np.float64), 1.0))))


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


def gained_range(rec: NodeCalibration, axis: str | None, gains: tuple[float, ...],
                 headroom: float) -> tuple[float, tuple[float, ...]]:
    r"""Full scale and charging samples of a value carrying ``gains`` along ``axis``.

    Without gains: ``max_part · headroom`` and the part quantiles.  With gains
    ``g`` and per-index maxima ``m`` along ``axis``: ``headroom · max_r g_r μ m_r``
    (a later stage: margin ``μ`` = :data:`GAIN_MARGIN`, no floor) and the
    ``axis_quantiles`` (parts over their index's maximum) times ``median(g·m)``;
    without axis profiles, ``max_part · max g · headroom`` and no samples.

    Parameters
    ----------
    rec : NodeCalibration
        The value's calibration record.
    axis : str or None
        The axis the gains run along (None: no gains).
    gains : tuple of float
        One gain per index of ``axis``.
    headroom : float
        The calibration headroom.

    Returns
    -------
    (float, tuple of float)
        The full scale and the charging samples (value units, gains applied).

    Examples
    --------
    >>> from compiler.calibration import measure
    >>> rec = measure("x", np.array([[4.0, 1.0], [2.0, 0.5]]), axes=("chirp", "range"))
    >>> gained_range(rec, "range", (1.0, 4.0), 1.0)[0]  # max(1·1.25·4, 4·1.25·1)
    5.0
    >>> gained_range(rec, None, (), 2.0)[0]
    8.0
    """
    if axis is None:
        return rec.max_part * headroom, tuple(rec.part_quantiles)
    g = np.asarray(gains)
    if axis not in rec.axis_max:
        return rec.max_part * float(g.max()) * headroom, ()
    m = np.asarray(rec.axis_max[axis])
    # axis_quantiles are of values / m; under gains g they scale by g·m (median index).
    c = float(np.median(g * m))
    full = float((g * GAIN_MARGIN * m).max()) * headroom  # later stages: margin, no floor
    return full, tuple(c * q for q in rec.axis_quantiles[axis])
