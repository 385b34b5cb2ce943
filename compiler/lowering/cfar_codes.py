r"""Latency codes of the spiking CFAR motifs: the value range and the code each variant uses.

OS-CFAR: log code with the threshold factor as a delay
------------------------------------------------------
With the log code ``t(x) = s·(ln x_max − ln x)`` (``s`` steps per neper) a factor
becomes a shift: ``t(x/α) = t(x) + s·ln α``.  The OS decision
``x_CUT > α·x_(k)`` holds iff fewer than ``k`` training cells satisfy
``α·x_j >= x_CUT``, i.e. arrive no later than the CUT's spike delayed by
``D_real = s·ln α`` (for ``α < 1`` the training spikes are delayed instead).  The
code's range is chosen so that ``D_real`` is exactly

* ``D`` (an integer) for ``ties="exact"``: in continuous time the network makes
  the conventional decision on every cell (equal arrivals are summed before the
  threshold test, which is the strict ``>``).  On a step grid every error is a
  missed detection (a training cell rounded into the CUT's bin blocks it);
* ``D + 1/2`` for ``ties="balanced"`` (the default on step grids): nearest
  rounding then splits the same-bin collisions evenly between the two orders —
  a *neighbour delay of half a step* — which halves the expected number of
  wrong comparisons and balances missed and extra detections.

The range ``[x_lo, x_hi]`` comes from the calibration quantiles (default 1 % and
100 %, the calibration maximum: clipping the top blocks a CUT above ``x_hi`` — the
strongest targets, so the top is not clipped by default — and the bottom only
silences cells that cannot be detections), then ``x_lo`` is lowered until
``s·ln α`` lands on ``D`` or ``D + 1/2``.  The whole budget of ``T`` steps is the
code window: a CUT whose delayed spike would arrive after ``T`` has
``x_CUT < α·x_lo`` and is not a detection (unless its ``k``-th training value is
below the range, which the bottom quantile makes rare), so it is simply dropped.

CA-CFAR: linear code with the offset folded into a delay
--------------------------------------------------------
A ramp neuron (``du = dv = 0``) that receives a spike at ``a`` with weight ``w``
holds ``w·(T − a)`` at the end of the window ``T``.  With the linear code
``t(x) = c·(x_hi − x)``, ``c = T/(x_hi − x_lo)``, the CUT weight ``n_avail``
delayed by ``d = c·x_lo·(α − 1)`` steps and training weights ``−α``:

.. math:: v(T) = c\,\bigl(n_{avail}\,x_{CUT} - \alpha \textstyle\sum_j x_j\bigr)

exactly (for every neuron, whatever its ``n_avail``), so ``v(T) > 0`` is the
CA decision.  A CUT that arrives after ``T`` has ``x_CUT <= α·x_lo <= α·mean`` and
is correctly not detected.  ``d`` must be an integer, so ``x_lo`` is lowered to
``d·x_hi / (T(α − 1) + d)`` with ``d = floor(c·x_lo·(α − 1))``.  The top of the
range is the 99.9 % calibration quantile (clipping biases the training sum, so
it clips less than OS).

Examples
--------
>>> code, d_cut, d_train, info = os_log_code(1.0, 100.0, alpha=2.0, n_steps=40, ties="exact")
>>> code.kind, code.t_max, d_cut, d_train, round(info["delay_real"], 9)
('log', 40, 6, 0, 6.0)
>>> code, d = ca_linear_code(0.0, 8.0, alpha=1.5, n_steps=17)
>>> (code.x_min, code.x_max, code.t_max, d)
(0.0, 8.0, 16, 0)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from compiler.snn import LatencyCode
from ir.errors import CompileError

__all__ = ["TIE_RULES", "RANGE_QUANTILES", "input_range", "os_log_code", "ca_linear_code"]

#: How an OS-CFAR network resolves a training spike in the CUT's time bin.
TIE_RULES = ("balanced", "exact")

#: Default (low, high) calibration quantiles of the encoded range, per CFAR kind.
RANGE_QUANTILES: dict[str, tuple[float, float]] = {"os": (0.01, 1.0), "ca": (0.0, 0.999)}


def _field(record: Any, name: str) -> Any:
    if isinstance(record, Mapping):
        return record.get(name)
    return getattr(record, name, None)


def input_range(record: Any, quantiles: tuple[float, float], *, node: str,
                source: str) -> tuple[float, float, str]:
    """The ``(x_lo, x_hi, how)`` a CFAR encodes, from a calibration record of its input.

    Parameters
    ----------
    record : NodeCalibration, mapping or None
        The calibrate pass's record of the input node (``min``, ``max`` and, for
        non-negative values, the quantiles ``abs_quantiles``).
    quantiles : (float, float)
        Quantiles of the range ends (used when the record has quantiles).
    node, source : str
        The CFAR node and its input node (for messages).

    Returns
    -------
    x_lo, x_hi : float
    how : str
        ``"quantiles"`` or ``"min-max"``.

    Raises
    ------
    CompileError
        Without a record, or when the record holds no usable range.

    Examples
    --------
    >>> input_range({"min": 2.0, "max": 9.0}, (0.0, 1.0), node="det", source="rd")
    (2.0, 9.0, 'min-max')
    >>> q = list(np.linspace(0.0, 10.0, 257))
    >>> input_range({"min": 0.0, "max": 10.0, "abs_quantiles": q}, (0.5, 1.0), node="d", source="r")
    (5.0, 10.0, 'quantiles')
    """
    if record is None:
        raise CompileError(
            f"node {node!r} (cfar): no calibration for its input {source!r}, so the latency "
            "code has no value range; run the calibrate pass (compile_graph(..., "
            "calibration_inputs={...}) or input_bounds), give the compile option "
            f"cfar_range={{'{node}': (x_lo, x_hi)}}, or choose motif 'host' for it",
            node=node)
    lo, hi = _field(record, "min"), _field(record, "max")
    qs = _field(record, "abs_quantiles") or ()
    how = "min-max"
    if qs and lo is not None and lo >= 0:
        grid = np.linspace(0.0, 1.0, len(qs))
        lo, hi = (float(np.interp(q, grid, np.asarray(qs, float))) for q in quantiles)
        how = "quantiles"
    if lo is None or hi is None or not (math.isfinite(lo) and math.isfinite(hi)) or hi <= 0:
        raise CompileError(
            f"node {node!r} (cfar): calibration of {source!r} gives the range [{lo}, {hi}]; "
            "the spiking CFAR needs a finite range with a positive maximum; pass "
            f"cfar_range={{'{node}': (x_lo, x_hi)}}", node=node)
    return float(lo), float(hi), how


def os_log_code(x_lo: float, x_hi: float, *, alpha: float, n_steps: int,
                ties: str = "balanced") -> tuple[LatencyCode, int, int, dict[str, Any]]:
    """The log latency code and delays of an OS-CFAR network of at most ``n_steps`` steps.

    Parameters
    ----------
    x_lo, x_hi : float
        Wanted range; ``x_lo <= 0`` is replaced by ``x_hi · 1e-9`` (90 dB below).
    alpha : float
        Threshold factor ``> 0``.
    n_steps : int
        Steps of the network, all of them the code window ``[0, T)``; a CUT
        delayed beyond it has ``x_CUT < α·x_lo`` and cannot be a detection.
    ties : {"balanced", "exact"}
        ``s·ln α`` lands on ``D + 1/2`` or on ``D`` (see the module docstring).

    Returns
    -------
    code : LatencyCode
        ``kind="log"``, ``t_min=0``, nearest rounding, ``x_min <= x_lo``.
    cut_delay, train_delay : int
        Delay of the CUT synapse (``α > 1``) or of every training synapse (``α < 1``).
    info : dict
        ``steps_per_neper``, ``delay_real`` (``s·|ln α|``), the range asked for.

    Raises
    ------
    CompileError
        For an unknown tie rule or a budget under 4 steps.
    """
    if ties not in TIE_RULES:
        raise CompileError(f"cfar_ties={ties!r} is not a tie rule; use one of {TIE_RULES}")
    if n_steps < 4:
        raise CompileError(f"a spiking OS-CFAR needs at least 4 time steps, got {n_steps}")
    x_lo = x_lo if x_lo > 0 else x_hi * 1e-9
    if x_lo >= x_hi:
        x_lo = x_hi / 2.0
    l0, a = math.log(x_hi / x_lo), abs(math.log(alpha))
    half = 0.5 if ties == "balanced" and a > 0 else 0.0
    t_max = n_steps
    delay = max(int(math.floor(t_max / l0 * a - half)), 0) if a > 0 else 0
    if a > 0 and delay + half == 0:
        delay = 1
    span = t_max * a / (delay + half) if a > 0 else l0
    code = LatencyCode(kind="log", t_min=0, t_max=t_max, x_min=x_hi * math.exp(-span),
                       x_max=x_hi, rounding="nearest")
    info = {"steps_per_neper": t_max / span, "delay_real": t_max / span * a,
            "range_asked": [x_lo, x_hi], "ties": ties}
    return code, (delay if alpha > 1 else 0), (delay if alpha < 1 else 0), info


def ca_linear_code(x_lo: float, x_hi: float, *, alpha: float,
                   n_steps: int) -> tuple[LatencyCode, int]:
    """The linear latency code and CUT delay of a CA-CFAR network of ``n_steps`` steps.

    Parameters
    ----------
    x_lo, x_hi : float
        Wanted range (``x_lo <= 0`` or ``alpha <= 1`` use ``x_lo = 0``, no delay).
    alpha : float
        Threshold factor ``> 0``.
    n_steps : int
        Total steps: the code window ``T = n_steps − 1`` plus the decision step.

    Returns
    -------
    code : LatencyCode
        ``kind="linear"``, ``t_min=0``, ``t_max=T``, nearest rounding.
    cut_delay : int
        ``d = c·x_lo·(α − 1)`` (exact by construction of ``x_lo``).

    Raises
    ------
    CompileError
        For a budget under 3 steps.
    """
    if n_steps < 3:
        raise CompileError(f"a spiking CA-CFAR needs at least 3 time steps, got {n_steps}")
    t_max = n_steps - 1
    x_lo = min(x_lo, x_hi / 2.0)
    delay = 0
    if x_lo > 0 and alpha > 1:
        delay = int(math.floor(t_max * x_lo * (alpha - 1) / (x_hi - x_lo)))
        x_lo = delay * x_hi / (t_max * (alpha - 1) + delay)
    else:
        x_lo = 0.0
    code = LatencyCode(kind="linear", t_min=0, t_max=t_max, x_min=x_lo, x_max=x_hi,
                       rounding="nearest")
    return code, delay
