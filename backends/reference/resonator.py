r"""Resonators in the reference simulator: the pure step function, the step engine's live
population and the closed form (the neuron of :mod:`compiler.snn.resonator`).

Per step, with ``d`` the summed input folded from the four compartments
(``d = (I_0 − I_1) + i(I_2 − I_3)``):

* input on: ``z ← a (z + d)`` (``a_end`` on the block-end steps of a renormalised
  population, ``renorm[t]``) and every compartment's membrane is ``v_c = σ_c(z)``
  (``σ = (Re, −Re, Im, −Im)``); the biases of input phases must be 0;
* input off: ``z`` is held and ``v_c ← v_c + b(t)`` — the charging stage of the ramp
  neurons, so a fire-once compartment spikes at the first step with ``v_c ≥ v_th``.

**Closed form.**  The input stage is a linear recurrence, so after the steps
``s0 … s1−1`` (drive ``d_j``)

.. math:: z(s_1) = a^{s_1 - s_0} z(s_0) + \sum_{j=s_0}^{s_1-1} a^{s_1 - j}\, d_j

with ``a^m = ρ^m e^{imθ}`` evaluated directly (no repeated products); the charging
stage uses the ramp neurons' analytic crossing
(:func:`backends.reference.spans.charge`).  In fixed point (``coef_bits > 0``) the
rounding makes the recurrence non-linear and the steps are replayed.  The closed form of
``run_closed`` is :mod:`backends.reference.resonator_closed` (every resonator, repetition
and frame at once, bit-identical to the step engine in fixed point);
:func:`solve_resonator` here is the plain one over the full drive histogram, kept as its
reference.  In floating point the engines agree to rounding
(``tests/test_resonator_sim.py``).

Examples
--------
A one-bin resonator at ``θ = −π/2`` fed ``1, 0, 0, 0``: the state turns a quarter per step.

>>> import numpy as np
>>> from compiler.snn.resonator import Phase, ResonatorParams
>>> p = ResonatorStepParams.of(ResonatorParams(axis="k", cos=(0.0,), sin=(-1.0,)), 4,
...                            shape={"k": 1, "part": 4})
>>> state, zs = ResonatorState.zeros(1), []
>>> for t, x in enumerate([1.0, 0.0, 0.0, 0.0]):
...     _, state = resonator_step(state, np.array([x, 0.0, 0.0, 0.0]), p, t)
...     zs.append(complex(state.x[0], state.y[0]) + 0)
>>> zs
[-1j, (-1+0j), 1j, (1+0j)]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from backends.reference.neuron import StepParams
from compiler.snn.resonator import N_COMPARTMENTS, ResonatorParams

__all__ = ["ResonatorStepParams", "ResonatorState", "resonator_step", "LiveResonators",
           "rotate", "solve_resonator"]

_SIGN = np.array([1, -1, 1, -1])


@dataclass(frozen=True, eq=False)
class ResonatorStepParams(StepParams):
    """:class:`StepParams` plus the coefficients of every resonator of one frame."""

    cos: np.ndarray | None = None
    sin: np.ndarray | None = None
    coef_bits: int = 0
    cos_end: np.ndarray | None = None
    sin_end: np.ndarray | None = None
    renorm: np.ndarray | None = None

    @classmethod
    def of(cls, params: ResonatorParams, n_steps: int, integer: bool = False,
           shape: dict[str, int] | None = None) -> ResonatorStepParams:
        """Resolve ``params`` for a population of ``shape`` over ``n_steps`` steps."""
        base = StepParams.from_params(params, n_steps, integer, shape)
        shape = shape or {params.axis: params.n_bins, "part": 4}
        dt = np.int64 if integer else np.float64
        c, s = (a.astype(dt) for a in params.per_resonator(shape))
        ends = {}
        if params.renorm_steps:
            ce, se = (a.astype(dt) for a in params.per_resonator(shape, end=True))
            ends = {"cos_end": ce, "sin_end": se, "renorm": params.renorm_schedule(n_steps)}
        fields = {k: getattr(base, k) for k in base.__dataclass_fields__}
        return cls(**fields, cos=c, sin=s, coef_bits=params.coef_bits, **ends)

    def tiled(self, n_res: int, end: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """``(cos, sin)`` for ``n_res`` resonators (whole frames); ``end``: the block-end
        coefficients."""
        c, s = (self.cos_end, self.sin_end) if end else (self.cos, self.sin)
        reps = n_res // c.size
        return np.tile(c, reps), np.tile(s, reps)

    def at_block_end(self, t: int) -> bool:
        """Whether step ``t`` rotates by the block-end coefficients."""
        return self.renorm is not None and bool(self.renorm[t])


class ResonatorState(NamedTuple):
    """``z = x + iy`` per resonator, compartment membranes ``v`` and fire-once flags."""

    x: np.ndarray
    y: np.ndarray
    v: np.ndarray
    fired: np.ndarray

    @classmethod
    def zeros(cls, n_res: int, integer: bool = False) -> ResonatorState:
        """The state before step 0 (``n_res`` resonators, four compartments each)."""
        dt = np.int64 if integer else np.float64
        return cls(np.zeros(n_res, dt), np.zeros(n_res, dt),
                   np.zeros(n_res * N_COMPARTMENTS, dt), np.zeros(n_res * N_COMPARTMENTS, bool))


def _shift(q: np.ndarray, bits: int, integer: bool) -> np.ndarray:
    """``q / 2^bits`` rounded half away from zero (exact in both arithmetics)."""
    if integer:
        return np.sign(q) * ((np.abs(q) + (1 << (bits - 1))) >> bits)
    return np.sign(q) * np.floor(np.abs(q) * 2.0 ** -bits + 0.5)


def rotate(x: np.ndarray, y: np.ndarray, c: np.ndarray, s: np.ndarray, bits: int,
           integer: bool) -> tuple[np.ndarray, np.ndarray]:
    """One rotation ``a·(x + iy)``: float products, or fixed point rounded to the nearest.

    Examples
    --------
    >>> import numpy as np
    >>> [a.tolist() for a in rotate(np.array([100]), np.array([0]), np.array([2896]),
    ...                             np.array([2896]), 12, True)]
    [[71], [71]]
    """
    if bits == 0:
        return c * x - s * y, s * x + c * y
    return _shift(c * x - s * y, bits, integer), _shift(s * x + c * y, bits, integer)


def _fold(current: np.ndarray | float, n_res: int, dtype) -> tuple[np.ndarray, np.ndarray]:
    cur = np.broadcast_to(np.asarray(current, dtype), (n_res * N_COMPARTMENTS,))
    cur = cur.reshape(n_res, N_COMPARTMENTS)
    return cur[:, 0] - cur[:, 1], cur[:, 2] - cur[:, 3]


def _project(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Compartment membranes ``(x, −x, y, −y)`` per resonator, flat."""
    return (np.stack([x, y], axis=1)[:, [0, 0, 1, 1]] * _SIGN).reshape(-1)


def resonator_step(state: ResonatorState, current: np.ndarray | float,
                   params: ResonatorStepParams, t: int) -> tuple[np.ndarray, ResonatorState]:
    """Advance a resonator population by step ``t``: ``(spikes, state)``.

    Parameters
    ----------
    state : ResonatorState
        After step ``t − 1``.
    current : ndarray or scalar
        Synaptic input per compartment (ignored while the input is off).
    params : ResonatorStepParams
    t : int

    Returns
    -------
    spikes : ndarray of bool
        Per compartment.
    state : ResonatorState
    """
    n_res = state.x.size
    integer = params.integer
    if params.input_on[t]:
        dx, dy = _fold(current, n_res, state.x.dtype)
        c, s = params.tiled(n_res, params.at_block_end(t))
        x, y = rotate(state.x + dx, state.y + dy, c, s, params.coef_bits, integer)
        v = _project(x, y)
    else:
        x, y = state.x, state.y
        v = state.v + params.per_neuron(params.bias[t], state.v.size)
    v_th = params.per_neuron(params.v_th, state.v.size)
    spikes = (v >= v_th) & ~state.fired if params.spiking_on[t] else np.zeros(v.shape, bool)
    return spikes, ResonatorState(x, y, v, state.fired | spikes)


class LiveResonators:
    """The step engine's resonator population (the interface of ``LiveNeurons``).

    Examples
    --------
    >>> from compiler.snn.resonator import Phase, ResonatorParams
    >>> p = ResonatorStepParams.of(ResonatorParams(axis="k", cos=(1.0,), sin=(0.0,), v_th=2.0,
    ...     phases=(Phase(start_step=0, spiking_on=False),
    ...             Phase(start_step=1, bias=1.0, input_on=False))), 3, shape={"k": 1, "part": 4})
    >>> def add(c, out):
    ...     out += c
    >>> live = LiveResonators(p, 4)
    >>> [live.step(t, [np.array([1.0, 0.0, 0.0, 0.0])], add).tolist() for t in range(3)]
    [[], [0], [2, 3]]
    """

    def __init__(self, params: ResonatorStepParams, n: int) -> None:
        self.params = params
        self.state = ResonatorState.zeros(n // N_COMPARTMENTS, params.integer)
        self._current = np.zeros(n, self.state.x.dtype)

    @property
    def v(self) -> np.ndarray:
        """Compartment membranes (flat, frames first)."""
        return self.state.v

    def takes_input(self, t: int) -> bool:
        """Whether the input phase is on at step ``t``."""
        return bool(self.params.input_on[t])

    def step(self, t: int, contributions, add) -> np.ndarray:
        """Advance by step ``t``; the flat indices of the compartments that spiked."""
        cur = 0
        if self.params.input_on[t] and contributions:
            cur = self._current
            cur.fill(0)
            for c in contributions:
                add(c, cur)
        spikes, self.state = resonator_step(self.state, cur, self.params, t)
        return np.flatnonzero(spikes)


def solve_resonator(params: ResonatorStepParams, drive_of, n: int, first: np.ndarray,
                    charge) -> np.ndarray:
    """The plain closed form of one population (the reference of
    :mod:`backends.reference.resonator_closed`): end membranes; fills ``first``.

    Parameters
    ----------
    params : ResonatorStepParams
    drive_of : callable
        ``drive_of(start, stop)`` → drive histogram ``(stop − start, n)`` of the steps.
    n : int
        Compartments (frames × population size).
    first : ndarray of int64
        First spike step per compartment (−1: none), filled in place.
    charge : callable
        :func:`backends.reference.spans.charge`.
    """
    n_res = n // N_COMPARTMENTS
    state = ResonatorState.zeros(n_res, params.integer)
    x, y, v = state.x, state.y, state.v
    c, s = params.tiled(n_res)
    ends = params.tiled(n_res, end=True) if params.renorm is not None else (c, s)
    chunk = max(1, (4 << 20) // max(1, n))
    for seg in params.spans:
        if not seg.input_on:
            _, v = charge(v, first, seg, params)
            continue
        for s0 in range(seg.start, seg.stop, chunk):
            s1 = min(seg.stop, s0 + chunk)
            drive = drive_of(s0, s1).reshape(s1 - s0, n_res, N_COMPARTMENTS)
            dx, dy = drive[..., 0] - drive[..., 1], drive[..., 2] - drive[..., 3]
            if params.coef_bits == 0:
                x, y = _power_sum(x, y, dx, dy, c, s)
            else:
                for j in range(s1 - s0):  # fixed point: the step arithmetic itself
                    cj, sj = ends if params.at_block_end(s0 + j) else (c, s)
                    x, y = rotate(x + dx[j], y + dy[j], cj, sj, params.coef_bits,
                                  params.integer)
        v = _project(x, y)
    return v


def _power_sum(x, y, dx, dy, c, s):
    """``a^m z + Σ_j a^{m−j} d_j`` with ``a^k = |a|^k e^{ikθ}`` (``m`` steps)."""
    m = dx.shape[0]
    rho, theta = np.hypot(c, s), np.arctan2(s, c)
    k = np.arange(m, 0, -1, dtype=np.float64)[:, None]  # a^(m - j) for j = 0 … m−1
    p = rho[None] ** k * np.exp(1j * k * theta[None])
    z = (x + 1j * y) * rho ** m * np.exp(1j * m * theta) + np.sum(p * (dx + 1j * dy), axis=0)
    return z.real.copy(), z.imag.copy()
