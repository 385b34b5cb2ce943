"""Cited figures: a number with the source it comes from, and a chip's energy per operation.

A :class:`Figure` is a value (``None``: not published) and the text that says where it
comes from — a paper and its table, a datasheet, or ``assumption: …`` with the reasoning —
so the resource report can print every constant beside the figure it produced.
:class:`EnergyFigures` are a profile's optional energy constants (``energy:`` in its YAML,
``docs/hardware.md``).

Examples
--------
>>> f = Figure(value=2.36e-11, source="Davies et al. 2018, Table 2")
>>> f.value, f.published
(2.36e-11, True)
>>> Figure(value=None, source="not published").published
False
>>> EnergyFigures.model_validate({"synaptic_op_j": {"value": 1, "source": "x"}}).spike_j is None
True
"""

from __future__ import annotations

from pydantic import ConfigDict, Field

from ir.errors import CompileValidationError
from ir.model import CheckedModel

__all__ = ["EnergyFigures", "Figure"]


class Figure(CheckedModel):
    """A constant and its source.

    Parameters
    ----------
    value : float or None
        The number in SI units (J, W, Hz, cycles); ``None`` where nothing is published.
    source : str
        Where it comes from (paper and table, datasheet), ``derived: …`` with the
        arithmetic, or ``assumption: …`` with the reasoning.
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    error_class = CompileValidationError

    value: float | None = Field(default=None, ge=0)
    source: str = Field(min_length=1)

    @property
    def published(self) -> bool:
        """Whether there is a number to use."""
        return self.value is not None


class EnergyFigures(CheckedModel):
    """A chip's energy per operation (each a :class:`Figure`; ``None``: not given).

    Parameters
    ----------
    synaptic_op_j : Figure, optional
        One synaptic event: a spike delivered over one synapse, J.
    neuron_update_j : Figure, optional
        One neuron's update in one time step, J.
    spike_j : Figure, optional
        One spike sent by a neuron (its message to the cores it reaches), J.
    static_power_w : Figure, optional
        Leakage of one chip while it runs, W (times the chips used and the frame's latency).
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = CompileValidationError

    synaptic_op_j: Figure | None = None
    neuron_update_j: Figure | None = None
    spike_j: Figure | None = None
    static_power_w: Figure | None = None
