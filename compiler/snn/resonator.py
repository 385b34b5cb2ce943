r"""The resonate-and-fire neuron of the ``resonator`` motif: a rotating 2-D state per bin.

A population of resonators has a trailing ``part`` axis of four *compartments*
``(+Re, −Re, +Im, −Im)`` per resonator; they are the four threshold read-outs of one
two-dimensional state ``z = x + i y`` (the ± pairs mirror each other, as the
``re_im_signed`` split of the time-coded motifs).  Per step ``t``:

.. math::

    d[t] &= (I_0 - I_1) + i\,(I_2 - I_3)          &\text{(summed synaptic input per compartment)}\\
    z[t] &= a_k\,(z[t-1] + d[t])                  &\text{(input phase on: rotate)}\\
    z[t] &= z[t-1]                                &\text{(input phase off: hold)}\\
    v_c[t] &= \sigma_c(z[t]) + \textstyle\sum_{s \le t,\ \text{input off}} b(s) \\
    s_c[t] &= [v_c[t] \ge v_{th}] \wedge \text{spiking on} \wedge \text{not fired}

with ``σ = (Re, −Re, Im, −Im)``, the bin's coefficient ``a_k = ρ e^{iθ_k}`` and fire-once
compartments.  Fed ``x[n]`` at steps ``n = 0 … N−1`` with ``θ_k = 2πk/N``, the state
ends at ``z = Σ_n x[n] a_k^{N−n} = Σ_n x[n] ρ^{N−n} e^{−2πikn/N}`` (``e^{2πik} = 1``):
the DFT bin ``X_k`` for ``ρ = 1`` (an exponential window ``ρ^{N−n}`` otherwise), with no
N × N weight matrix — the sample reaches every bin through one fan-out synapse.

**Fixed point** (``coef_bits = F > 0``): ``cos``/``sin`` are whole numbers ``C, S`` with
``C² + S² ≤ 4^F`` (``|a| ≤ 1``: no exponential growth), and the rotation rounds half
away from zero: ``x' = rnd((C·x̃ − S·ỹ)/2^F)``, ``y' = rnd((S·x̃ + C·ỹ)/2^F)`` with
``x̃ + iỹ = z + d`` (at most half a unit per component and step).  Both arithmetics
(float64 and int64) compute it exactly the same way.
``coef_bits = 0`` multiplies by the float coefficients.

**Periodic renormalisation** (``renorm_steps = M > 0``, fixed point only): within each
input span, the steps ``stop − 1, stop − 1 − M, …`` (every ``M``-th step, counted back from
the span's last one) rotate by a second coefficient ``ĉ_k = (C'_k + iS'_k)/2^F`` instead
of ``â_k``, chosen so that a block's product ``â^{M−1}ĉ`` is the exact ``a^M`` to one
rounding (:mod:`compiler.lowering.resonator_fixed`).  Every component is at most ``2^F``
in magnitude and every block's product at most 1 in modulus: the state does not grow
over a block.  On a chip this is one more coefficient pair per bin and a step counter in
the neuron program (an assumption about a programmable neuron, as the resonator itself).

Examples
--------
>>> p = ResonatorParams(axis="k", cos=(1.0, 0.0), sin=(0.0, -1.0), v_th=4.0,
...                     phases=(Phase(start_step=0, spiking_on=False),
...                             Phase(start_step=4, bias=1.0, input_on=False)))
>>> p.is_ramp, p.n_bins, p.is_integer()
(True, 2, False)
"""

from __future__ import annotations

import numpy as np
from pydantic import model_validator

from compiler.snn.neurons import NeuronParams, Phase, ResetMode

__all__ = ["ResonatorParams", "N_COMPARTMENTS", "Phase"]

#: Compartments per resonator on the trailing ``part`` axis: ``(+Re, −Re, +Im, −Im)``.
N_COMPARTMENTS = 4


class ResonatorParams(NeuronParams):
    """Parameters of a resonator population (see the module docstring).

    Parameters
    ----------
    axis : str
        The population axis along which each index has its own coefficient (the bins).
    cos, sin : tuple of float
        ``Re a_k`` and ``Im a_k`` per index of ``axis`` (times ``2^coef_bits`` in fixed point).
    coef_bits : int
        Fraction bits of the fixed-point coefficients (0: floating point).
    renorm_steps : int
        ``M``: every ``M``-th input step, counted back from the last, rotates by
        ``(cos_end, sin_end)`` (0: never; see the module docstring).
    cos_end, sin_end : tuple of float
        The block-end coefficients per index of ``axis`` (``renorm_steps > 0`` only).
    du, dv, reset :
        Fixed: a resonator has no current or voltage decay of its own (``ρ`` is in ``a_k``)
        and fire-once compartments.
    scale_axis, scales :
        Optional per-bin read-out scales along ``axis`` (threshold and biases times
        ``c_k``, as for :class:`~compiler.snn.NeuronParams`).

    Examples
    --------
    >>> ResonatorParams(axis="k", cos=(4096.0,), sin=(0.0,), coef_bits=12).is_integer()
    True
    """

    du: float = 0.0
    dv: float = 0.0
    reset: ResetMode = "fire_once"
    phases: tuple[Phase, ...] = (Phase(start_step=0, spiking_on=False),)
    axis: str
    cos: tuple[float, ...]
    sin: tuple[float, ...]
    coef_bits: int = 0
    renorm_steps: int = 0
    cos_end: tuple[float, ...] = ()
    sin_end: tuple[float, ...] = ()

    @model_validator(mode="after")
    def _resonator(self) -> ResonatorParams:
        if not self.cos or len(self.cos) != len(self.sin):
            raise ValueError(f"cos and sin need one value per index of {self.axis!r}; got "
                             f"{len(self.cos)} and {len(self.sin)}")
        if self.du != 0.0 or self.dv != 0.0 or self.reset != "fire_once":
            raise ValueError("a resonator has du = dv = 0 and reset='fire_once'; got "
                             f"du={self.du}, dv={self.dv}, reset={self.reset!r}")
        if self.scale_axis not in (None, self.axis):
            raise ValueError(f"a resonator's per-neuron scales run along its axis {self.axis!r}"
                             f", not {self.scale_axis!r}")
        if any(p.input_on and p.spiking_on for p in self.phases):
            raise ValueError("a resonator rotates while its input is on and may spike only "
                             "while it is off; no phase may have both on")
        if not 0 <= self.coef_bits <= 30:
            raise ValueError(f"coef_bits must be in 0..30, got {self.coef_bits}")
        c, s = np.asarray(self.cos), np.asarray(self.sin)
        one = 4.0 ** self.coef_bits
        if self.coef_bits and not (np.all(c == np.rint(c)) and np.all(s == np.rint(s))):
            raise ValueError("fixed-point coefficients (coef_bits > 0) must be whole numbers")
        if self.renorm_steps:
            return self._renormalised(c, s)
        if self.cos_end or self.sin_end:
            raise ValueError("cos_end and sin_end are for renorm_steps > 0")
        big = c * c + s * s > one * (1 + 1e-12)
        if big.any():
            raise ValueError(f"|a_k| must be at most 1 (a bounded state); index "
                             f"{int(np.argmax(big))} has |a| = "
                             f"{float(np.sqrt((c * c + s * s)[big][0] / one)):.6f}")
        return self

    def _renormalised(self, c: np.ndarray, s: np.ndarray) -> ResonatorParams:
        m, f = self.renorm_steps, self.coef_bits
        if m < 2 or f == 0:
            raise ValueError(f"renorm_steps must be 0 or >= 2 and needs fixed-point "
                             f"coefficients (coef_bits > 0); got renorm_steps={m}, "
                             f"coef_bits={f}")
        if len(self.cos_end) != self.n_bins or len(self.sin_end) != self.n_bins:
            raise ValueError(f"cos_end and sin_end need one value per index of {self.axis!r} "
                             f"({self.n_bins}); got {len(self.cos_end)} and "
                             f"{len(self.sin_end)}")
        ce, se = np.asarray(self.cos_end), np.asarray(self.sin_end)
        if not (np.all(ce == np.rint(ce)) and np.all(se == np.rint(se))):
            raise ValueError("fixed-point coefficients (coef_bits > 0) must be whole numbers")
        top = np.max(np.abs(np.concatenate([c, s, ce, se])))
        if top > 2.0 ** f:
            raise ValueError(f"coefficient components must be at most 2^{f} = {2 ** f} in "
                             f"magnitude; got {top:.0f}")
        block = ((c * c + s * s) / 4.0 ** f) ** ((m - 1) / 2) * np.hypot(ce, se) / 2.0 ** f
        if np.any(block > 1 + 1e-9):
            k = int(np.argmax(block))
            raise ValueError(f"a block of {m} steps must not grow the state: index {k} has "
                             f"|a|^{m - 1}|a_end| = {block[k]:.6f} > 1")
        return self

    @property
    def n_bins(self) -> int:
        """Number of indices along :attr:`axis` (coefficients)."""
        return len(self.cos)

    def is_integer(self) -> bool:
        """Valid for int64 arithmetic: whole thresholds/biases and fixed-point coefficients."""
        return self.coef_bits > 0 and super().is_integer()

    def renorm_schedule(self, n_steps: int) -> np.ndarray:
        """Per step, whether it rotates by the block-end coefficient (``renorm_steps``).

        Examples
        --------
        >>> p = ResonatorParams(axis="k", cos=(4096.0,), sin=(0.0,), coef_bits=12,
        ...                     renorm_steps=2, cos_end=(4096.0,), sin_end=(0.0,),
        ...                     phases=(Phase(start_step=0, spiking_on=False),
        ...                             Phase(start_step=5, input_on=False)))
        >>> p.renorm_schedule(7).astype(int).tolist()
        [1, 0, 1, 0, 1, 0, 0]
        """
        out = np.zeros(n_steps, bool)
        if not self.renorm_steps:
            return out
        on = np.concatenate([[False], self.schedule(n_steps)[1], [False]]).astype(np.int8)
        edges = np.diff(on)
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        for start, stop in zip(starts, stops, strict=True):
            out[np.arange(stop - 1, start - 1, -self.renorm_steps)] = True
        return out

    def per_resonator(self, shape: dict[str, int], end: bool = False
                      ) -> tuple[np.ndarray, np.ndarray]:
        """``(cos, sin)`` per resonator, flattened over ``shape`` without its ``part`` axis
        (``end``: the block-end coefficients of a renormalised population).

        Examples
        --------
        >>> p = ResonatorParams(axis="k", cos=(1.0, 0.5), sin=(0.0, 0.5))
        >>> [a.tolist() for a in p.per_resonator({"c": 2, "k": 2, "part": 4})]
        [[1.0, 0.5, 1.0, 0.5], [0.0, 0.5, 0.0, 0.5]]
        """
        axes = [a for a in shape if a != "part"]
        view = [1] * len(axes)
        view[axes.index(self.axis)] = self.n_bins
        dims = tuple(shape[a] for a in axes)
        out = []
        for values in ((self.cos_end, self.sin_end) if end else (self.cos, self.sin)):
            a = np.asarray(values, np.float64).reshape(view)
            out.append(np.broadcast_to(a, dims).reshape(-1).copy())
        return out[0], out[1]
