r"""The one neuron model of radarsnn: current-based IF/LIF in discrete time (Loihi-like).

Every neuron population uses the same update, evaluated once per time step
``t = 0 … n_steps-1`` in this exact order (the reference simulator, its
closed-form fast path and every exporter follow it to the letter):

.. math::

    I[t] &= \sum_{p} \sum_{j} w_{pj}\, s_j[t - d_{pj}]            \\
    u[t] &= (1 - d_u)\, u[t-1] + I[t]       &\text{(input phase on)}\\
    u[t] &= 0                               &\text{(input phase off)}\\
    v[t] &= (1 - d_v)\, v[t-1] + (u[t] + b(t))                    \\
    s[t] &= [v[t] \ge v_{th}] \wedge \text{spiking phase on} \wedge \text{not fired (fire-once)}

then, for neurons that spiked, the reset: ``value`` sets ``v = v_reset``,
``subtract`` sets ``v = v - v_th``, ``fire_once`` leaves ``v`` alone and silences
the neuron for the rest of the frame.  ``u[-1] = v[-1] = 0``.  Note the
bracket: ``u[t] + b(t)`` is added to the decayed ``v`` as one term.

``d_u = 0, d_v = 0`` is the non-leaky *ramp* neuron of the time-coded motifs
(``V(T) = Σ w (T - t_in)``); ``d_u = 1`` makes the current instantaneous (plain
IF, or LIF with ``d_v > 0``).

The bias ``b(t)`` and the two switches follow a :class:`Phase` schedule:
piecewise constant from each phase's ``start_step`` to the next one's.
``input_on=False`` cuts the synaptic current (``u = 0``; spikes arriving then are
dropped), ``spiking_on=False`` clamps the output (the membrane still integrates).

Integer (fixed-point) arithmetic follows the same order with integer
``v_th``, ``v_reset``, biases and weights, and decays given as multiples of
``2**-12``: ``x·(1 - d)`` is computed as ``trunc(x·(4096 - D) / 4096)`` with
``D = d·4096`` (rounding toward zero, as Loihi does).

Examples
--------
The S-FT neuron of a 100-step window: silent stage, then a charging stage with
bias ``2·v_th/T`` and the input cut.

>>> p = NeuronParams(du=0.0, dv=0.0, v_th=50.0, reset="fire_once",
...                  phases=(Phase(start_step=0, bias=0.0, spiking_on=False),
...                          Phase(start_step=100, bias=1.0, input_on=False)))
>>> bias, input_on, spiking_on = p.schedule(n_steps=200)
>>> float(bias[99]), float(bias[100]), bool(input_on[100]), bool(spiking_on[99])
(0.0, 1.0, False, False)
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import ConfigDict, Field, field_validator, model_validator

from ir.errors import NetworkValidationError
from ir.model import CheckedModel

__all__ = ["DECAY_ONE", "Phase", "NeuronParams", "ResetMode"]

#: Fixed-point denominator of the decay constants in integer arithmetic (Loihi: 12 bits).
DECAY_ONE = 4096

ResetMode = Literal["value", "subtract", "fire_once"]


class Phase(CheckedModel):
    """One stage of a neuron population's schedule, from ``start_step`` until the next phase.

    Parameters
    ----------
    start_step : int
        First time step of the phase (the first phase must start at 0).
    bias : float
        Constant bias current ``b(t)`` added every step of the phase.
    input_on : bool
        Whether synaptic input reaches the neuron; ``False`` sets ``u = 0``.
    spiking_on : bool
        Whether the neuron may spike; ``False`` clamps the output.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = NetworkValidationError

    start_step: int = Field(ge=0)
    bias: float = 0.0
    input_on: bool = True
    spiking_on: bool = True

    @field_validator("bias")
    @classmethod
    def _finite(cls, value: float) -> float:
        if not np.isfinite(value):
            raise ValueError(f"bias must be finite, got {value}")
        return value


class NeuronParams(CheckedModel):
    """Parameters shared by every neuron of one population.

    Parameters
    ----------
    du, dv : float
        Current and voltage decay per step, in ``[0, 1]`` (0 = no leak).
    v_th : float
        Firing threshold (``v >= v_th`` spikes); must be positive.
    reset : {"value", "subtract", "fire_once"}
        What a spike does to the membrane.
    v_reset : float
        Membrane value after a spike with ``reset="value"``.
    phases : tuple of Phase
        The bias / input / spiking schedule; starts at step 0, strictly increasing.
    scale_axis : str, optional
        An axis of the population along which each neuron has its own **parameter
        scale** ``c_i = scales[i]``: its threshold, reset value and every bias are
        ``c_i`` times the shared ones (``c_i·v_th``, ``c_i·v_reset``, ``c_i·b(t)``).
        A non-leaky ramp neuron with scale ``c`` fires when ``V/c + B(k) ≥ v_th``: it
        reads its membrane ``c`` times coarser, so one population can give each index
        of that axis its own full scale (the per-neuron gains of the time-coded motifs;
        on a chip: per-neuron bias exponents and thresholds, or per-neuron initial
        membranes, see ``docs/hardware.md``).
    scales : tuple of float
        One positive scale per index of ``scale_axis`` (whole numbers in integer
        arithmetic).

    Examples
    --------
    >>> NeuronParams(v_th=1.0).is_ramp
    False
    >>> NeuronParams(du=0.0, dv=0.0, v_th=1.0).is_ramp
    True
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = NetworkValidationError

    du: float = Field(default=1.0, ge=0.0, le=1.0)
    dv: float = Field(default=0.0, ge=0.0, le=1.0)
    v_th: float = 1.0
    reset: ResetMode = "subtract"
    v_reset: float = 0.0
    phases: tuple[Phase, ...] = (Phase(start_step=0),)
    scale_axis: str | None = None
    scales: tuple[float, ...] = ()

    @field_validator("v_th")
    @classmethod
    def _positive_threshold(cls, value: float) -> float:
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"v_th must be a positive finite number, got {value}")
        return value

    @field_validator("v_reset")
    @classmethod
    def _finite_reset(cls, value: float) -> float:
        if not np.isfinite(value):
            raise ValueError(f"v_reset must be finite, got {value}")
        return value

    @model_validator(mode="after")
    def _schedule(self) -> NeuronParams:
        starts = [p.start_step for p in self.phases]
        if not starts or starts[0] != 0:
            raise ValueError(f"the first phase must start at step 0, got starts {starts}")
        if any(b <= a for a, b in zip(starts, starts[1:], strict=False)):
            raise ValueError(f"phase start steps must increase strictly, got {starts}")
        return self

    @model_validator(mode="after")
    def _scales(self) -> NeuronParams:
        if (self.scale_axis is None) != (not self.scales):
            raise ValueError("scale_axis and scales go together: give both or neither, got "
                             f"scale_axis={self.scale_axis!r} and {len(self.scales)} scales")
        bad = [c for c in self.scales if not (np.isfinite(c) and c > 0)]
        if bad:
            raise ValueError(f"per-neuron scales must be positive finite numbers, got {bad[:3]}")
        return self

    def scale_of(self, shape: dict[str, int]) -> np.ndarray | None:
        """The per-neuron scales flattened over a population of ``shape`` (None: no scales).

        Examples
        --------
        >>> p = NeuronParams(scale_axis="r", scales=(1.0, 4.0))
        >>> p.scale_of({"r": 2, "part": 2}).tolist()
        [1.0, 1.0, 4.0, 4.0]
        """
        if self.scale_axis is None:
            return None
        axes = list(shape)
        view = [1] * len(axes)
        view[axes.index(self.scale_axis)] = len(self.scales)
        c = np.asarray(self.scales, dtype=np.float64).reshape(view)
        return np.broadcast_to(c, tuple(shape.values())).reshape(-1).copy()

    @property
    def is_ramp(self) -> bool:
        """True for the non-leaky ramp neuron (``du = dv = 0``) of the time-coded motifs."""
        return self.du == 0.0 and self.dv == 0.0

    def phase_index(self, n_steps: int) -> np.ndarray:
        """The index of the phase in force at each step ``0 … n_steps-1``.

        Examples
        --------
        >>> p = NeuronParams(phases=(Phase(start_step=0), Phase(start_step=2, bias=0.5)))
        >>> p.phase_index(4).tolist()
        [0, 0, 1, 1]
        """
        starts = np.array([p.start_step for p in self.phases])
        return np.searchsorted(starts, np.arange(n_steps), side="right") - 1

    def schedule(self, n_steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-step ``(bias, input_on, spiking_on)`` arrays of length ``n_steps``.

        Examples
        --------
        >>> p = NeuronParams(phases=(Phase(start_step=0, spiking_on=False),
        ...                          Phase(start_step=2, bias=0.5, input_on=False)))
        >>> bias, inp, spk = p.schedule(3)
        >>> bias.tolist(), inp.tolist(), spk.tolist()
        ([0.0, 0.0, 0.5], [True, True, False], [False, False, True])
        """
        idx = self.phase_index(n_steps)
        bias = np.array([p.bias for p in self.phases], dtype=np.float64)[idx]
        input_on = np.array([p.input_on for p in self.phases], dtype=bool)[idx]
        spiking_on = np.array([p.spiking_on for p in self.phases], dtype=bool)[idx]
        return bias, input_on, spiking_on

    def is_integer(self) -> bool:
        """Whether the parameters are valid for integer (fixed-point) arithmetic.

        Thresholds, resets and biases must be whole numbers and the decays
        multiples of ``1/4096``.

        Examples
        --------
        >>> NeuronParams(v_th=64.0, du=0.5).is_integer()
        True
        >>> NeuronParams(v_th=1.5).is_integer()
        False
        """
        values = [self.v_th, self.v_reset, *(p.bias for p in self.phases), *self.scales]
        decays = [self.du * DECAY_ONE, self.dv * DECAY_ONE]
        return all(float(x).is_integer() for x in values + decays)
