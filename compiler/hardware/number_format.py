"""The number formats of a target: how a chip stores weights, thresholds, biases and state.

A :class:`NumberFormat` is one part of a :class:`~compiler.hardware.HardwareProfile`
(``profile.number_format``).  A profile file lists its fields flat, beside the budgets
(``weight_bits: 8``, not nested); the profile builds this record on load and writes it
back flat.  ``None`` in a width means *no such limit*: floating-point weights and
thresholds, an unbounded state, binary spikes only, any delay.

Examples
--------
>>> fmt = NumberFormat(weight_bits=8, threshold_bits=18, threshold_mantissa_bits=17,
...                    delay_bits=6)
>>> fmt.integer, fmt.threshold_max, fmt.max_delay_steps
(True, 131071, 63)
>>> NumberFormat().integer, NumberFormat().threshold_max, NumberFormat().state_width
(False, None, 24)
"""

from __future__ import annotations

from typing import Annotated

from pydantic import ConfigDict, Field, Strict

from ir.errors import CompileValidationError
from ir.model import CheckedModel

__all__ = ["NOMINAL_STATE_BITS", "NUMBER_FORMAT_FIELDS", "NumberFormat"]

_Int = Annotated[int, Strict()]  # not True, not 1.0: a width is an integer
_Width = _Int | None
_Bool = Annotated[bool, Strict()]  # not 1, not "yes"

#: The state width a motif scales to where the target gives none (``state_bits: null``):
#: the 24 bits of Loihi's ``u`` and ``v`` (Davies et al. 2018).
NOMINAL_STATE_BITS = 24


class NumberFormat(CheckedModel):
    """How one target stores numbers (``None``: no limit, floating point).

    Parameters
    ----------
    weight_bits, threshold_bits : int or None
        Signed integer width of a weight mantissa and of thresholds/biases/membranes
        in state units (``None``: floating point, no quantization).
    weight_exponent_max : int
        Weights are ``mantissa·2^e`` with one exponent ``e ∈ [0, weight_exponent_max]``
        per projection (a synapse format); 0: plain integers.
    threshold_mantissa_bits, threshold_shift : int or None, int
        Thresholds are an unsigned mantissa of that width times ``2^threshold_shift``
        (``None``: any integer up to the ``threshold_bits`` limit).
    bias_mantissa_bits, bias_exponent_max : int or None, int
        Biases are a signed mantissa of that width times ``2^e``, ``0 ≤ e ≤ max``.
    state_bits : int or None
        Signed width of the neuron state ``u``, ``v`` in state units (not wrapped or
        saturated by the simulator: a run counts the states beyond it).
    graded_spike_bits : int or None
        Payload width of graded spikes (``None``: binary spikes only).
    per_neuron_scales : bool
        Whether each neuron may have its own bias and threshold (or initial membrane),
        which the per-neuron gains of the time-coded motifs need.
    delay_bits : int or None
        Width of a synaptic delay; the largest delay is ``2**delay_bits - 1`` steps.
    current_decay_offset_lsb : int
        The current decay the chip adds to every ``du``, in ``1/4096`` per step (Loihi 1:
        1, so ``du = 0``, a non-leaking current, does not exist).

    Examples
    --------
    >>> fmt = NumberFormat(weight_bits=8, weight_exponent_max=8, bias_mantissa_bits=13)
    >>> fmt.integer, fmt.bias_max, fmt.state_width
    (True, 4095, 24)
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = CompileValidationError

    weight_bits: _Width = Field(default=None, ge=2, le=64)
    threshold_bits: _Width = Field(default=None, ge=2, le=64)
    weight_exponent_max: _Int = Field(default=0, ge=0, le=32)
    threshold_mantissa_bits: _Width = Field(default=None, ge=1, le=64)
    threshold_shift: _Int = Field(default=0, ge=0, le=32)
    bias_mantissa_bits: _Width = Field(default=None, ge=2, le=64)
    bias_exponent_max: _Int = Field(default=0, ge=0, le=32)
    state_bits: _Width = Field(default=None, ge=2, le=64)
    graded_spike_bits: _Width = Field(default=None, ge=2, le=64)
    per_neuron_scales: _Bool = False
    delay_bits: _Width = Field(default=None, ge=0, le=32)
    current_decay_offset_lsb: _Int = Field(default=0, ge=0, le=4096)

    @property
    def integer(self) -> bool:
        """Whether weights are integers (``weight_bits`` given): the program is quantized."""
        return self.weight_bits is not None

    @property
    def state_width(self) -> int:
        """``state_bits``, or :data:`NOMINAL_STATE_BITS` where the state is unbounded."""
        return self.state_bits or NOMINAL_STATE_BITS

    @property
    def max_delay_steps(self) -> int | None:
        """Largest synaptic delay, ``2**delay_bits - 1`` steps (``None``: unbounded)."""
        return None if self.delay_bits is None else (1 << self.delay_bits) - 1

    @property
    def threshold_max(self) -> int | None:
        """Largest threshold in state units (``None``: unbounded).

        Examples
        --------
        >>> NumberFormat(threshold_bits=18).threshold_max
        131071
        >>> NumberFormat(threshold_mantissa_bits=4, threshold_shift=2).threshold_max
        60
        """
        limits = []
        if self.threshold_bits is not None:
            limits.append((1 << (self.threshold_bits - 1)) - 1)
        if self.threshold_mantissa_bits is not None:
            limits.append(((1 << self.threshold_mantissa_bits) - 1) << self.threshold_shift)
        return min(limits) if limits else None

    @property
    def bias_max(self) -> int | None:
        """Largest whole bias, ``(2^(bias_mantissa_bits−1) − 1)·2^bias_exponent_max``
        (``None``: unbounded).

        Examples
        --------
        >>> NumberFormat(bias_mantissa_bits=13, bias_exponent_max=1).bias_max
        8190
        """
        if self.bias_mantissa_bits is None:
            return None
        return ((1 << (self.bias_mantissa_bits - 1)) - 1) << self.bias_exponent_max


#: The fields of a number format, as a profile file lists them (flat, among the budgets).
NUMBER_FORMAT_FIELDS: tuple[str, ...] = tuple(NumberFormat.model_fields)
