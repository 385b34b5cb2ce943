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

The step engine runs the same update in place
(:class:`backends.reference.live_neurons.LiveNeurons`).

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

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from compiler.snn.neurons import DECAY_ONE, NeuronParams

__all__ = ["NeuronState", "PhaseSpan", "StepParams", "decay", "neuron_step"]


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


class PhaseSpan(NamedTuple):
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
    spans : tuple of PhaseSpan
        The phase schedule clipped to ``[0, n_steps)``.
    integer : bool
        Integer (fixed-point) arithmetic.
    scale : ndarray or None
        Per-neuron parameter scales flattened over the population (``None``: all 1;
        :attr:`compiler.snn.NeuronParams.scales`): neuron ``i`` uses ``scale[i]·v_th``,
        ``scale[i]·v_reset`` and ``scale[i]·bias[t]``.  State arrays hold whole frames of
        neurons, so :meth:`per_neuron` tiles it over the frames.
    """

    du: float
    dv: float
    v_th: float | int
    v_reset: float | int
    reset: str
    bias: np.ndarray
    input_on: np.ndarray
    spiking_on: np.ndarray
    spans: tuple[PhaseSpan, ...]
    integer: bool = False
    scale: np.ndarray | None = None

    def per_neuron(self, value: float | int, n: int) -> float | int | np.ndarray:
        """``value`` for each of ``n`` neurons (whole frames): scalar without scales.

        Examples
        --------
        >>> from compiler.snn import NeuronParams
        >>> p = StepParams.from_params(NeuronParams(v_th=2.0, scale_axis="r", scales=(1, 4)),
        ...                            n_steps=1, shape={"r": 2})
        >>> p.per_neuron(p.v_th, 4).tolist(), StepParams.from_params(NeuronParams(), 1).per_neuron(
        ...     3.0, 4)
        ([2.0, 8.0, 2.0, 8.0], 3.0)
        """
        if self.scale is None:
            return value
        return value * np.tile(self.scale, n // self.scale.size)

    @classmethod
    def from_params(cls, params: NeuronParams, n_steps: int, integer: bool = False,
                    shape: dict[str, int] | None = None) -> StepParams:
        """Resolve a population's :class:`~compiler.snn.NeuronParams` over ``n_steps`` steps.

        Parameters
        ----------
        params : NeuronParams
            The population's parameters (already checked to be integer when ``integer``).
        n_steps : int
            Steps per frame.
        integer : bool
            Convert thresholds, resets and biases to integers.
        shape : dict, optional
            The population's shape (needed when ``params`` has per-neuron scales).

        Returns
        -------
        StepParams

        Examples
        --------
        >>> from compiler.snn import NeuronParams, Phase
        >>> p = NeuronParams(phases=(Phase(start_step=0), Phase(start_step=3, bias=2.0)))
        >>> [tuple(s) for s in StepParams.from_params(p, n_steps=5, integer=True).spans]
        [(0, 3, 0, True, True), (3, 5, 2, True, True)]
        """
        bias, input_on, spiking_on = params.schedule(n_steps)
        cast = int if integer else float
        starts = [ph.start_step for ph in params.phases] + [n_steps]
        spans = tuple(
            PhaseSpan(start, min(stop, n_steps), cast(ph.bias), ph.input_on, ph.spiking_on)
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
            spans=spans,
            integer=integer,
            scale=_flat_scale(params, shape, integer),
        )


def _flat_scale(params: NeuronParams, shape: dict[str, int] | None,
                integer: bool) -> np.ndarray | None:
    if params.scale_axis is None:
        return None
    if shape is None:
        raise ValueError("per-neuron scales need the population's shape")
    scale = params.scale_of(shape)
    return scale.astype(np.int64) if integer else scale


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
    n = state.v.size
    v = decay(state.v, params.dv, params.integer) + (u + params.per_neuron(params.bias[t], n))
    v_th = params.per_neuron(params.v_th, n)
    if params.spiking_on[t]:
        spikes = v >= v_th
    else:
        spikes = np.zeros(v.shape, bool)
    if params.reset == "fire_once":
        spikes &= ~state.fired
    elif params.reset == "value":
        v = np.where(spikes, params.per_neuron(params.v_reset, n), v)
    else:
        v = np.where(spikes, v - v_th, v)
    return spikes, NeuronState(u, v, state.fired | spikes)
