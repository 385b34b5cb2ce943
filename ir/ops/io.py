"""Graph inputs and outputs: ``adc_input``, ``input`` and ``output``.

Inputs have no reference implementation (their values are given to
:func:`ir.interpreter.evaluate`) and no propagated calibration bound.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, PositiveFloat, PositiveInt, model_validator

from ir.model import Name
from ir.ops.base import Op
from ir.types import Domain, TensorType

__all__ = ["AdcInput", "Input", "Output"]


class AdcInput(Op):
    """Raw FMCW ADC samples of one frame: ``x[..., chirp, sample]`` amplitudes.

    Parameters
    ----------
    shape : dict[str, int]
        Axis name -> size in array order, e.g. ``{"rx": 4, "chirp": 64, "sample": 256}``.
    complex : bool, default False
        True for I/Q (complex baseband) capture, False for real-only ADCs.
    full_scale : float, optional
        The ADC's full scale per rail in the input's units (``2**(adc_bits - 1)``
        codes): no sample exceeds it.  Without calibration data the ``calibrate``
        pass bounds every stage from it (``docs/fourier.md``).

    Notes
    -----
    Output type: ``TensorType(axes=shape, complex=complex, domain="amplitude")``.
    Takes no inputs; its value is supplied to :func:`ir.interpreter.evaluate`.

    Examples
    --------
    >>> AdcInput(shape={"chirp": 2, "sample": 4}, complex=True).infer("adc", [])
    TensorType(axes={'chirp': 2, 'sample': 4}, complex=True, domain='amplitude')
    """

    arity: ClassVar[int] = 0
    no_bound: ClassVar[str] = "a graph input: bounded by its ADC full scale, not propagated"
    op: Literal["adc_input"] = "adc_input"
    shape: dict[Name, PositiveInt] = Field(min_length=1)
    complex: bool = False
    full_scale: PositiveFloat | None = None

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        self.expect_inputs(node_id, inputs)
        return TensorType(axes=self.shape, complex=self.complex, domain="amplitude")


class Input(Op):
    """A generic named tensor fed to the graph (e.g. a stored range-Doppler map).

    Parameters
    ----------
    shape : dict[str, int]
        Axis name -> size in array order.
    complex : bool, default False
        Whether values are complex (only with domain ``amplitude``).
    domain : {"amplitude", "power", "db", "mask"}, default "amplitude"
        What the values mean.

    Notes
    -----
    Output type: ``TensorType(axes=shape, complex=complex, domain=domain)``.

    Examples
    --------
    >>> Input(shape={"range": 8}, domain="power").infer("rd", []).domain
    'power'
    """

    arity: ClassVar[int] = 0
    no_bound: ClassVar[str] = "a graph input: bounded by the option input_bounds, not propagated"
    op: Literal["input"] = "input"
    shape: dict[Name, PositiveInt] = Field(min_length=1)
    complex: bool = False
    domain: Domain = "amplitude"

    @model_validator(mode="after")
    def _real_unless_amplitude(self) -> Input:
        if self.complex and self.domain != "amplitude":
            raise ValueError(f"domain {self.domain!r} is real; only 'amplitude' may be complex")
        return self

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        self.expect_inputs(node_id, inputs)
        return TensorType(axes=self.shape, complex=self.complex, domain=self.domain)


class Output(Op):
    """Marks its input as a graph output: ``y = x`` (identity).

    Examples
    --------
    >>> t = TensorType(axes={"range": 8}, domain="mask")
    >>> Output().infer("out", [t]) == t
    True
    """

    is_output: ClassVar[bool] = True
    no_bound: ClassVar[str] = "passes its input through; nothing is lowered for it"
    op: Literal["output"] = "output"

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        return t

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return args[0]
