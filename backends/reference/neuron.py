r"""The pure neuron step function (Norse-style) of the one radarsnn neuron model.

:func:`neuron_step` advances a whole population by one time step,
``(state, current, params, t) -> (spikes, state)``, with small immutable
records for the state (:class:`NeuronState`) and the parameters
(:class:`StepParams`).  It evaluates :mod:`compiler.snn.neurons` to the letter:

.. math::

    u[t] &= (1 - d_u)\, u[t-1] + I[t]  \quad\text{(input on; else } u[t] = 0)\\
    v[t] &= (1 - d_v)\, v[t-1] + (u[t] + b(t))                             \\
    s[t] &= [v[t] \ge v_{th}] \wedge \text{spiking on} \wedge \neg\text{fired (fire-once)}

then the reset of the neurons that spiked (``value``: ``v = v_reset``;
``subtract``: ``v = v - v_th``; ``fire_once``: ``v`` untouched, neuron silenced).

In float64 the decay is the product ``(1.0 - d) * x``; in int64 it is
``trunc(x * (4096 - D) / 4096)`` with ``D = d * 4096`` (toward zero).  Both
simulation engines use these two functions, so they share one operation order.

:class:`LiveNeurons` is the step engine's in-place form of :func:`neuron_step`:
preallocated buffers, the same floating-point operations element by element,
and the operations that provably change nothing left out (see its Notes).

Examples
--------
An IF neuron (``du = 1``) with subtraction reset, driven by 0.375 per step:

>>> import numpy as np
>>> from compiler.snn import NeuronParams
>>> p = StepParams.from_params(NeuronParams(du=1.0, v_th=1.0, reset="subtract"), n_steps=4)
>>> state, out = NeuronState.zeros((1,)), []
>>> for t in range(4):
...     s, state = neuron_step(state, np.array([0.375]), p, t)
...     out.append((bool(s[0]), float(state.v[0])))
>>> out
[(False, 0.375), (False, 0.75), (True, 0.125), (False, 0.5)]
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from compiler.snn.neurons import DECAY_ONE, NeuronParams

__all__ = ["LiveNeurons", "NeuronState", "StepParams", "Segment", "decay", "neuron_step"]


class NeuronState(NamedTuple):
    """State of a population: current ``u``, membrane ``v``, and whether each neuron has fired."""

    u: np.ndarray
    v: np.ndarray
    fired: np.ndarray

    @classmethod
    def zeros(cls, shape: tuple[int, ...], integer: bool = False) -> NeuronState:
        """The state at ``t = -1``: ``u = v = 0``, nothing fired.

        Examples
        --------
        >>> NeuronState.zeros((2,), integer=True).v.dtype
        dtype('int64')
        """
        dtype = np.int64 if integer else np.float64
        return cls(np.zeros(shape, dtype), np.zeros(shape, dtype), np.zeros(shape, bool))


class Segment(NamedTuple):
    """A run of steps ``[start, stop)`` with constant bias and switches (a clipped phase)."""

    start: int
    stop: int
    bias: float | int
    input_on: bool
    spiking_on: bool


@dataclass(frozen=True, eq=False)
class StepParams:
    """Per-population constants of :func:`neuron_step`, resolved for ``n_steps`` steps.

    Parameters
    ----------
    du, dv : float
        Current and voltage decays per step (see :class:`compiler.snn.NeuronParams`).
    v_th, v_reset : float or int
        Threshold and reset value (Python ``int`` in integer arithmetic).
    reset : {"value", "subtract", "fire_once"}
        The reset rule.
    bias : ndarray
        Bias per step (float64, or int64 in integer arithmetic).
    input_on, spiking_on : ndarray of bool
        The two switches per step.
    segments : tuple of Segment
        The phase schedule clipped to ``[0, n_steps)``.
    integer : bool
        Integer (fixed-point) arithmetic.
    """

    du: float
    dv: float
    v_th: float | int
    v_reset: float | int
    reset: str
    bias: np.ndarray
    input_on: np.ndarray
    spiking_on: np.ndarray
    segments: tuple[Segment, ...]
    integer: bool = False

    @classmethod
    def from_params(cls, params: NeuronParams, n_steps: int, integer: bool = False) -> StepParams:
        """Resolve a population's :class:`~compiler.snn.NeuronParams` over ``n_steps`` steps.

        Parameters
        ----------
        params : NeuronParams
            The population's parameters (already checked to be integer when ``integer``).
        n_steps : int
            Steps per frame.
        integer : bool
            Convert thresholds, resets and biases to integers.

        Returns
        -------
        StepParams

        Examples
        --------
        >>> from compiler.snn import NeuronParams, Phase
        >>> p = NeuronParams(phases=(Phase(start_step=0), Phase(start_step=3, bias=2.0)))
        >>> [tuple(s) for s in StepParams.from_params(p, n_steps=5, integer=True).segments]
        [(0, 3, 0, True, True), (3, 5, 2, True, True)]
        """
        bias, input_on, spiking_on = params.schedule(n_steps)
        cast = int if integer else float
        starts = [ph.start_step for ph in params.phases] + [n_steps]
        segments = tuple(
            Segment(start, min(stop, n_steps), cast(ph.bias), ph.input_on, ph.spiking_on)
            for ph, start, stop in zip(params.phases, starts, starts[1:], strict=False)
            if start < n_steps
        )
        return cls(
            du=float(params.du),
            dv=float(params.dv),
            v_th=cast(params.v_th),
            v_reset=cast(params.v_reset),
            reset=params.reset,
            bias=bias.astype(np.int64) if integer else bias,
            input_on=input_on,
            spiking_on=spiking_on,
            segments=segments,
            integer=integer,
        )


def decay(x: np.ndarray, d: float, integer: bool = False) -> np.ndarray:
    r"""``x`` decayed by ``d`` for one step: ``(1 - d)·x``.

    Parameters
    ----------
    x : ndarray
        Values (float64, or int64 when ``integer``).
    d : float
        Decay per step in ``[0, 1]`` (a multiple of ``1/4096`` when ``integer``).
    integer : bool
        Fixed-point rule: ``trunc(x·(4096 - D) / 4096)`` with ``D = d·4096``.

    Returns
    -------
    ndarray
        A new array of the dtype of ``x``.

    Examples
    --------
    >>> import numpy as np
    >>> decay(np.array([7, -7]), 0.25, integer=True).tolist()
    [5, -5]
    >>> decay(np.array([1.0]), 0.25).tolist()
    [0.75]
    """
    if not integer:
        return (1.0 - d) * x
    keep = DECAY_ONE - round(d * DECAY_ONE)
    if keep == DECAY_ONE:
        return x.copy()
    if keep == 0:
        return np.zeros_like(x)
    q = x * keep
    return (q - np.fmod(q, DECAY_ONE)) // DECAY_ONE


def neuron_step(
    state: NeuronState, current: np.ndarray | float, params: StepParams, t: int
) -> tuple[np.ndarray, NeuronState]:
    """Advance a population by one step.

    Parameters
    ----------
    state : NeuronState
        The state after step ``t - 1``.
    current : ndarray or scalar
        The synaptic input ``I[t]`` (ignored where the input phase is off).
    params : StepParams
        The population's resolved parameters.
    t : int
        The step index (selects bias and switches).

    Returns
    -------
    spikes : ndarray of bool
        ``s[t]``.
    state : NeuronState
        The state after step ``t`` (reset applied).

    Examples
    --------
    A fire-once ramp neuron keeps integrating after its one spike:

    >>> import numpy as np
    >>> from compiler.snn import NeuronParams
    >>> p = StepParams.from_params(NeuronParams(du=0.0, dv=0.0, v_th=2.0, reset="fire_once"), 4)
    >>> state, spikes = NeuronState.zeros((1,)), []
    >>> for t in range(4):
    ...     s, state = neuron_step(state, np.array([1.0 if t == 0 else 0.0]), p, t)
    ...     spikes.append(bool(s[0]))
    >>> spikes, state.v.tolist()
    ([False, True, False, False], [4.0])
    """
    if params.input_on[t]:
        u = decay(state.u, params.du, params.integer) + current
    else:
        u = np.zeros_like(state.u)
    v = decay(state.v, params.dv, params.integer) + (u + params.bias[t])
    if params.spiking_on[t]:
        spikes = v >= params.v_th
    else:
        spikes = np.zeros(v.shape, bool)
    if params.reset == "fire_once":
        spikes &= ~state.fired
    elif params.reset == "value":
        v = np.where(spikes, params.v_reset, v)
    else:
        v = np.where(spikes, v - params.v_th, v)
    return spikes, NeuronState(u, v, state.fired | spikes)


#: ``add(contribution, out)`` adds one contribution's current into the flat array ``out``.
AddCurrent = Callable[[Any, np.ndarray], None]

_NO_SPIKES = np.zeros(0, np.int64)


class LiveNeurons:
    r"""One population's state in the step engine: :func:`neuron_step` in place.

    Holds flat ``u``, ``v`` (``n`` neurons, frames first) and preallocated
    scratch buffers; :meth:`step` advances them by one step and returns the flat
    indices of the neurons that spiked, ascending.

    Parameters
    ----------
    params : StepParams
        The population's resolved parameters.
    n : int
        Neurons (frames × population size).

    Notes
    -----
    Every array element goes through the floating-point operations of
    :func:`neuron_step`, in its order, except operations that cannot change a
    bit, which are skipped:

    * ``(1.0 - 0.0) * x`` (no decay) is ``x``; a decay of an all-``+0`` ``u`` is ``+0``.
    * ``x + 0.0`` is ``x`` unless ``x = -0.0``.  With ``du = 0`` (float), ``u``
      only ever sums from ``+0`` (``a + b = -0.0`` needs ``a = b = -0.0``), so it
      holds no ``-0.0``: a current is added to the rows it reaches only, a step
      without arrivals adds nothing, and ``u + 0.0`` (zero bias) is ``u``.  The
      same holds for ``v`` unless ``dv ≠ 0``, ``v_reset = -0.0`` or (``du ≠ 0``
      and some bias is ``-0.0``); then the ``+0`` additions are kept.
    * While the input is off ``u`` stays all ``+0`` (zeroed once); ``v + (0 + b)``
      becomes one scalar addition, skipped for ``b = 0`` where ``v`` holds no ``-0.0``.
    * The threshold test is skipped while ``v`` is unchanged since a test after
      which no neuron can spike at that ``v`` (fire-once: everyone at or above
      threshold has fired; other resets: the test found no spike).
    * Fire-once in float64 compares ``v`` with a per-neuron threshold that turns
      NaN when the neuron fires: ``v >= NaN`` is False, so one comparison gives
      ``(v >= v_th) and not fired``.

    Several contributions in one step are summed first from ``+0`` in a scratch
    buffer (``((0 + I_1) + I_2) + …``) and then added to ``u``, as
    :func:`neuron_step` adds the summed current.  Integer arithmetic is exact,
    so there the order is free.

    Examples
    --------
    The IF neuron of the module example, driven by 0.375 per step:

    >>> from compiler.snn import NeuronParams
    >>> p = StepParams.from_params(NeuronParams(du=1.0, v_th=1.0, reset="subtract"), n_steps=4)
    >>> def add(current, out):
    ...     out += current
    >>> live = LiveNeurons(p, 1)
    >>> [(live.step(t, [np.array([0.375])], add).tolist(), float(live.v[0])) for t in range(4)]
    [([], 0.375), ([], 0.75), ([0], 0.125), ([], 0.5)]
    """

    def __init__(self, params: StepParams, n: int) -> None:
        self.params = params
        integer = params.integer
        dtype = np.int64 if integer else np.float64
        self.u = np.zeros(n, dtype)
        self.v = np.zeros(n, dtype)
        self._spikes = np.empty(n, bool)
        self._scratch: np.ndarray | None = None
        once = params.reset == "fire_once"
        # fire-once: which neurons may still fire; in float64 as a threshold per neuron that
        # becomes NaN once it fired (v >= NaN is False): one comparison for both conditions
        self._threshold = np.full(n, params.v_th, np.float64) if once and not integer else None
        self._armed = np.ones(n, bool) if once and integer else None
        self._n_armed = n
        self._input_on = params.input_on.tolist()
        self._spiking_on = params.spiking_on.tolist()
        self._bias = params.bias.tolist()
        self._u_zero = True   # u is +0 everywhere
        self._clean = False   # v unchanged since a test that left nobody able to spike
        self._keep_u = None if params.du == 0.0 else 1.0 - params.du
        self._keep_v = None if params.dv == 0.0 else 1.0 - params.dv
        negative_zero_bias = bool(np.any(np.signbit(params.bias) & (params.bias == 0)))
        # whether u / v may hold -0.0, which x + 0.0 would turn into +0.0
        self._signed_u = not integer and params.du != 0.0
        self._signed_v = not integer and (
            params.dv != 0.0 or (self._signed_u and negative_zero_bias)
            or (params.reset == "value" and bool(np.signbit(params.v_reset))))

    def takes_input(self, t: int) -> bool:
        """Whether the input phase is on at step ``t`` (arrivals are dropped otherwise)."""
        return self._input_on[t]

    def step(self, t: int, contributions: Sequence[Any], add: AddCurrent) -> np.ndarray:
        """Advance by step ``t``; return the flat indices of the neurons that spiked.

        Parameters
        ----------
        t : int
            The step.
        contributions : sequence
            This step's current contributions (ignored while the input is off).
        add : callable
            ``add(contribution, out)`` adds one contribution's current into ``out``.

        Returns
        -------
        ndarray of int64
            Spiking neurons, ascending.
        """
        if self._input_on[t]:
            self._integrate(contributions, add)
        elif not self._u_zero:
            self.u.fill(0)
            self._u_zero = True
        self._update_v(t)
        if not self._spiking_on[t] or self._clean:
            return _NO_SPIKES
        return self._fire()

    def _scratch_buffer(self) -> np.ndarray:
        if self._scratch is None:
            self._scratch = np.empty_like(self.u)
        return self._scratch

    def _integrate(self, contributions: Sequence[Any], add: AddCurrent) -> None:
        """``u = (1 - du)·u + I`` with ``I`` the summed contributions."""
        u, p = self.u, self.params
        if self._keep_u is not None and not self._u_zero:
            if p.integer:
                u[...] = decay(u, p.du, integer=True)
            else:
                np.multiply(u, self._keep_u, out=u)
        if not contributions:
            if self._signed_u:
                np.add(u, 0.0, out=u)  # neuron_step's ``+ 0``
            return
        self._u_zero = False
        if p.integer or (len(contributions) == 1 and not self._signed_u):
            for c in contributions:
                add(c, u)
            return
        current = self._scratch_buffer()
        current.fill(0)
        for c in contributions:
            add(c, current)
        np.add(u, current, out=u)

    def _update_v(self, t: int) -> None:
        """``v = (1 - dv)·v + (u + b)``."""
        v, p = self.v, self.params
        b = self._bias[t]
        if self._keep_v is not None:
            if p.integer:
                v[...] = decay(v, p.dv, integer=True)
            else:
                np.multiply(v, self._keep_v, out=v)
            self._clean = False
        if self._u_zero:
            b = b + 0 if p.integer else b + 0.0  # u + b with u = +0
            if b != 0 or self._signed_v:
                np.add(v, b, out=v)
                self._clean = False
        elif b == 0 and not self._signed_u:
            np.add(v, self.u, out=v)
            self._clean = False
        else:
            term = self._scratch_buffer()
            np.add(self.u, b, out=term)
            np.add(v, term, out=v)
            self._clean = False

    def _fire(self) -> np.ndarray:
        """Threshold test and reset; spiking is on."""
        p, v, spikes = self.params, self.v, self._spikes
        armed, threshold = self._armed, self._threshold
        once = armed is not None or threshold is not None
        if once and self._n_armed == 0:
            self._clean = True
            return _NO_SPIKES
        if threshold is not None:
            np.greater_equal(v, threshold, out=spikes)
        else:
            np.greater_equal(v, p.v_th, out=spikes)
            if armed is not None:
                np.logical_and(spikes, armed, out=spikes)
        if not spikes.any():
            self._clean = True
            return _NO_SPIKES
        fired = spikes.nonzero()[0]
        if once:
            if threshold is not None:
                threshold[fired] = np.nan
            else:
                armed[fired] = False
            self._n_armed -= fired.size
            self._clean = True
        elif p.reset == "value":
            v[fired] = p.v_reset
        else:
            v[fired] -= p.v_th
        return fired
