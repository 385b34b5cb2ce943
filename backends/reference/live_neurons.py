r"""The step engine's in-place neuron update: :func:`~backends.reference.neuron.neuron_step`
with preallocated buffers, the same floating-point operations element by element, and the
operations that provably change nothing left out (see :class:`LiveNeurons`' Notes).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from backends.reference.neuron import StepParams, decay

__all__ = ["AddCurrent", "LiveNeurons"]


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
    state_limit : int, optional
        The chip's state range ``±state_limit``: each step, the
        neurons whose ``u`` or ``v`` lies beyond it after the update (before the threshold
        test) are counted in :attr:`overflow` — where the chip's 24-bit ``u`` would wrap
        and its ``v`` saturate (and a saturated ``v`` fire); the engine keeps computing
        in ``int64``.

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

    def __init__(self, params: StepParams, n: int, state_limit: int | None = None) -> None:
        self.params = params
        self.state_limit = state_limit
        self.overflow = 0  # neuron-steps with u or v beyond ±state_limit
        integer = params.integer
        dtype = np.int64 if integer else np.float64
        self.u = np.zeros(n, dtype)
        self.v = np.zeros(n, dtype)
        self._spikes = np.empty(n, bool)
        self._scratch: np.ndarray | None = None
        once = params.reset == "fire_once"
        # fire-once: which neurons may still fire; in float64 as a threshold per neuron that
        # becomes NaN once it fired (v >= NaN is False): one comparison for both conditions
        # per-neuron scales: threshold, reset and each bias as arrays over the n neurons
        self._v_th = params.per_neuron(params.v_th, n)
        self._v_reset = params.per_neuron(params.v_reset, n)
        self._scaled_bias = {} if params.scale is None else {
            b: params.per_neuron(b, n) for b in set(params.bias.tolist())}
        self._threshold = (np.array(np.broadcast_to(self._v_th, (n,)), np.float64)
                           if once and not integer else None)
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
        if self.state_limit is not None:
            self._count_overflow()
        if not self._spiking_on[t] or self._clean:
            return _NO_SPIKES
        return self._fire()

    def _count_overflow(self) -> None:
        """Count the neurons whose ``u`` or ``v`` left ``±state_limit`` this step."""
        limit = self.state_limit
        out = (self.u > limit) | (self.u < -limit) | (self.v > limit) | (self.v < -limit)
        self.overflow += int(np.count_nonzero(out))

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
        if self._scaled_bias and b != 0:  # per-neuron bias c·b: v + (u + c·b)
            cb = self._scaled_bias[b]
            if self._u_zero:
                np.add(v, cb + 0 if p.integer else cb + 0.0, out=v)
            else:
                term = self._scratch_buffer()
                np.add(self.u, cb, out=term)
                np.add(v, term, out=v)
            self._clean = False
        elif self._u_zero:
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
            np.greater_equal(v, self._v_th, out=spikes)
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
            v[fired] = self._v_reset if np.ndim(self._v_reset) == 0 else self._v_reset[fired]
        else:
            v[fired] -= self._v_th if np.ndim(self._v_th) == 0 else self._v_th[fired]
        return fired
