r"""The radarsnn neuron model written in Brian2's equation language.

:func:`neuron_code` turns one population's :class:`~compiler.snn.NeuronParams`
into the strings and constants a Brian2 ``NeuronGroup`` needs.  The model has
no differential equations: the discrete-time update of
:mod:`compiler.snn.neurons` runs once per step as *abstract code* (Brian2
evaluates the statements in order, one assignment per line, so the grouping
``v = (1 - d_v) v + (u + b)`` survives its symbolic rewriting)::

    u  = input_on(t) * (keep_u * u + I_in)   # I_in: currents delivered this step
    ub = u + bias(t)
    v  = keep_v * v + ub
    I_in = 0

with ``keep_u = 1 - d_u`` and ``keep_v = 1 - d_v`` computed in float64 exactly
as the reference's ``(1.0 - d) * x``.  The schedule ``bias(t)``,
``input_on(t)`` and ``spiking_on(t)`` are ``TimedArray`` s of one value per
step (the population's :meth:`~compiler.snn.NeuronParams.schedule`).  The
threshold is ``v >= v_th and spiking_on(t) > 0.5`` (``and not fired`` for
``fire_once``) and the reset ``v = v_reset`` / ``v = v - v_th`` /
``fired = True``.

Examples
--------
>>> from compiler.snn import NeuronParams, Phase
>>> code = neuron_code(NeuronParams(du=0.0, v_th=4.0, reset="fire_once",
...                                 phases=(Phase(start_step=0, spiking_on=False),
...                                         Phase(start_step=2, bias=1.0, input_on=False))), 3)
>>> print(code.threshold)
v >= v_th and spiking_on(t) > 0.5 and not fired
>>> code.bias.tolist(), code.input_on.tolist(), code.constants["keep_u"]
([0.0, 0.0, 1.0], [1.0, 1.0, 0.0], 1.0)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from compiler.snn.neurons import NeuronParams

__all__ = ["NeuronCode", "neuron_code", "MODEL", "UPDATE", "RESETS"]

#: State variables of every group (``fired`` is used by ``fire_once`` only).
MODEL = "u : 1\nv : 1\nI_in : 1\nfired : boolean"

#: The per-step update, run after the step's currents were delivered into ``I_in``.
UPDATE = "u = input_on(t) * (keep_u * u + I_in)\nub = u + bias(t)\nv = keep_v * v + ub\nI_in = 0"

#: Reset code by reset mode.
RESETS = {"value": "v = v_reset", "subtract": "v = v - v_th", "fire_once": "fired = True"}


@dataclass(frozen=True, eq=False)
class NeuronCode:
    """What one ``NeuronGroup`` needs: code strings, constants and per-step schedules.

    Attributes
    ----------
    model, update, threshold, reset : str
        Brian2 equations, the per-step abstract code, threshold condition, reset code.
    constants : dict
        ``keep_u``, ``keep_v``, ``v_th``, ``v_reset`` (floats).
    bias, input_on, spiking_on : ndarray of float64
        One value per step, for ``TimedArray`` s named ``bias``, ``input_on``, ``spiking_on``.
    timed : dict
        Further per-step schedules by ``TimedArray`` name (a resonator's ``renorm``).
    """

    model: str
    update: str
    threshold: str
    reset: str
    constants: dict[str, float]
    bias: np.ndarray
    input_on: np.ndarray
    spiking_on: np.ndarray
    timed: dict[str, np.ndarray] = field(default_factory=dict)


def neuron_code(params: NeuronParams, n_steps: int) -> NeuronCode:
    """The Brian2 code of a population with ``params`` over a frame of ``n_steps`` steps.

    Parameters
    ----------
    params : NeuronParams
        The population's dynamics and schedule.
    n_steps : int
        Steps per frame (the length of the schedules).

    Returns
    -------
    NeuronCode

    Examples
    --------
    >>> from compiler.snn import NeuronParams
    >>> c = neuron_code(NeuronParams(du=1.0, dv=0.25, v_th=2.0, reset="value"), 2)
    >>> c.reset, c.constants["keep_v"], c.spiking_on.tolist()
    ('v = v_reset', 0.75, [1.0, 1.0])
    """
    bias, input_on, spiking_on = params.schedule(n_steps)
    model, update, reset = MODEL, UPDATE, RESETS[params.reset]
    threshold = "v >= v_th and spiking_on(t) > 0.5"
    if params.scale_axis is not None:  # per-neuron scales: a constant c per neuron
        model += "\nc : 1 (constant)"
        update = update.replace("u + bias(t)", "u + c * bias(t)")
        threshold = threshold.replace("v_th", "c * v_th")
        reset = reset.replace("v_th", "c * v_th").replace("= v_reset", "= c * v_reset")
    if params.reset == "fire_once":
        threshold += " and not fired"
    return NeuronCode(
        model=model, update=update, threshold=threshold, reset=reset,
        constants={"keep_u": 1.0 - float(params.du), "keep_v": 1.0 - float(params.dv),
                   "v_th": float(params.v_th), "v_reset": float(params.v_reset)},
        bias=bias.astype(np.float64), input_on=input_on.astype(np.float64),
        spiking_on=spiking_on.astype(np.float64))
