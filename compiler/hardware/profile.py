"""Hardware profiles: the budgets of a neuromorphic chip as data (built-in YAML or a user file).

A :class:`HardwareProfile` lists what one core can hold, how many cores there are, how
the chip stores numbers (its :class:`~compiler.hardware.number_format.NumberFormat`,
``profile.number_format``) and what its stock neurons do.  The compiler reads nothing
else about the target, so a new chip is a new YAML file, never new code.  Budgets given
as ``null`` are unbounded.  ``compile_graph`` loads the profile once and hands the same
typed record to every pass; a compile without a target reads :data:`NO_TARGET`.

Files are read by :func:`~compiler.hardware.loading.load_profile`
(:mod:`compiler.hardware.loading`).

Examples
--------
>>> p = HardwareProfile(name="mine", neurons_per_core=256, weight_bits=8)
>>> p.limits().tolist(), p.number_format.weight_bits, p.model_dump()["weight_bits"]
([256.0, inf, inf, inf], 8, 8)
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    ConfigDict,
    Field,
    Strict,
    field_validator,
    model_serializer,
    model_validator,
)

from compiler.hardware.figures import EnergyFigures
from compiler.hardware.number_format import NUMBER_FORMAT_FIELDS, NumberFormat
from ir.errors import BudgetError, CompileValidationError
from ir.model import CheckedModel

__all__ = ["BOARD_FIELDS", "BUDGETS", "BUILTIN_BOARDS", "BUILTIN_PROFILES", "FILE_FIELDS",
           "NO_TARGET", "OPTIONAL_FIELDS", "REQUIRED_FIELDS", "HardwareProfile"]

#: The per-core budgets, in the column order of every demand array.
BUDGETS: tuple[str, ...] = ("neurons", "input_axons", "output_axons", "synapse_bits")

#: Names of the profiles shipped in ``compiler/hardware/profiles/*.yaml``.
BUILTIN_PROFILES: tuple[str, ...] = ("loihi", "loihi2", "spinnaker2", "unbounded")

#: Multi-chip boards in ``compiler/hardware/boards/*.yaml`` (a chip profile, chips, links).
BUILTIN_BOARDS: tuple[str, ...] = ("kapoho_point", "nahuku32", "spinnaker2_48", "hala_point")

#: Fields only boards set; left out of the serialised profile when unset (``None``), so a
#: single-chip profile serialises as before they existed.
BOARD_FIELDS: tuple[str, ...] = ("chip_profile", "inter_chip_bandwidth_bit_s",
                                 "inter_chip_latency_s", "spike_message_bits")

#: Optional fields a profile file may leave out (``None``), also left out of the serialised
#: profile when unset: the board fields and the energy constants.
OPTIONAL_FIELDS: tuple[str, ...] = (*BOARD_FIELDS, "energy")

#: A profile's fields as a file lists them, flat: the number format's among the budgets.
#: A profile serialises in this order (a saved program's target is unchanged by the
#: :class:`~compiler.hardware.number_format.NumberFormat` record).
FILE_FIELDS: tuple[str, ...] = (
    "name", "cores_per_chip", "chips", "neurons_per_core", "input_axons_per_core",
    "output_axons_per_core", "synapse_memory_bits_per_core", "bits_per_synapse",
    "weight_bits", "threshold_bits", "weight_exponent_max", "threshold_mantissa_bits",
    "threshold_shift", "bias_mantissa_bits", "bias_exponent_max", "state_bits",
    "graded_spike_bits", "per_neuron_scales", "delay_bits", "max_steps_per_frame",
    "time_step_s", "shared_weights_per_core", "current_decay_offset_lsb", "full_voltage_decay",
    "reset", "fire_once", "threshold_schedule", "input_gate", "resonate_and_fire",
    *OPTIONAL_FIELDS[:-1], "energy", "description")

_Int = Annotated[int, Strict()]  # not True, not 1.0: a count is an integer
_Count = _Int | None
_Bool = Annotated[bool, Strict()]  # not 1, not "yes"


class HardwareProfile(CheckedModel):
    """The budgets of one neuromorphic target (``None`` = unbounded).

    Parameters
    ----------
    name : str
        Profile name.
    cores_per_chip, chips : int or None
        Cores on one chip and chips available.
    neurons_per_core : int or None
        Neurons (compartments) one core holds.
    input_axons_per_core, output_axons_per_core : int or None
        Fan-in lines (distinct source neurons reaching the core) and fan-out lines
        (one per neuron and target population it drives) per core.
    synapse_memory_bits_per_core : int or None
        Synaptic memory of one core, bits.
    bits_per_synapse : int
        Bits of one stored synapse entry (weight + delay + index).
    number_format : NumberFormat
        How the chip stores weights, thresholds, biases, state, graded payloads and
        delays (:class:`~compiler.hardware.number_format.NumberFormat`); a file gives its
        fields flat (``weight_bits: 8``), as :data:`FILE_FIELDS` lists them.
    max_steps_per_frame : int or None
        Time steps one frame may use.
    time_step_s : float or None
        Wall-clock duration of one time step, s (for the latency estimate).
    shared_weights_per_core : bool
        Whether a core stores a shared matrix or stencil kernel once for all the
        neurons it holds, instead of once per neuron/repetition.
    full_voltage_decay : bool
        Whether ``dv = 1`` (a membrane that forgets every step) exists (Loihi 1: the 12-bit
        ``dv`` register stops at 4095).
    reset : {"zero", "subtract", "programmable"}
        What a spike does to the membrane: ``v = 0`` only, ``v -= θ`` only, or any reset
        of the neuron model (``value``, ``subtract``, ``fire_once``).
    fire_once : {"none", "programmable"}
        Whether a neuron can be silenced for the rest of the frame after its spike.
    threshold_schedule : bool
        Whether spiking can be switched on or off between phases of a run.
    input_gate : bool
        Whether the synaptic input can be cut for a phase (spikes arriving then dropped).
    resonate_and_fire : bool
        Whether the chip has resonate-and-fire neurons (the ``resonator`` motif).
    chip_profile : str or None
        For a board: the chip profile it is made of (its per-core budgets and formats).
    inter_chip_bandwidth_bit_s : float or None
        Off-chip spike bandwidth of one chip, each direction, bit/s (``None``: not given).
    inter_chip_latency_s : float or None
        Delay a time step gains when its spikes cross a chip boundary, s.
    spike_message_bits : int or None
        Bits of one spike message on a chip-to-chip link.
    energy : EnergyFigures or None
        Energy per synaptic event, neuron update and spike, and static power, each with
        its source (:mod:`compiler.hardware.figures`; ``None``: no energy estimate).
    description : str
        Where the figures come from.
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    error_class = CompileValidationError

    name: str = Field(min_length=1)
    cores_per_chip: _Count = Field(default=None, ge=1)
    chips: _Count = Field(default=None, ge=1)
    neurons_per_core: _Count = Field(default=None, ge=1)
    input_axons_per_core: _Count = Field(default=None, ge=1)
    output_axons_per_core: _Count = Field(default=None, ge=1)
    synapse_memory_bits_per_core: _Count = Field(default=None, ge=1)
    bits_per_synapse: _Int = Field(default=64, ge=1)
    number_format: NumberFormat = NumberFormat()
    max_steps_per_frame: _Count = Field(default=None, ge=1)
    time_step_s: float | None = Field(default=None, gt=0)
    shared_weights_per_core: _Bool = False
    full_voltage_decay: _Bool = True
    reset: Literal["zero", "subtract", "programmable"] = "programmable"
    fire_once: Literal["none", "programmable"] = "programmable"
    threshold_schedule: _Bool = True
    input_gate: _Bool = True
    resonate_and_fire: _Bool = True
    chip_profile: str | None = None
    inter_chip_bandwidth_bit_s: float | None = Field(default=None, gt=0)
    inter_chip_latency_s: float | None = Field(default=None, ge=0)
    spike_message_bits: _Count = Field(default=None, ge=1, le=1024)
    energy: EnergyFigures | None = None
    description: str = ""

    @field_validator("time_step_s", "inter_chip_bandwidth_bit_s", "inter_chip_latency_s",
                     mode="before")
    @classmethod
    def _a_number(cls, value: Any) -> Any:
        # a string stays allowed: PyYAML reads ``1e-5`` (no dot) as the string '1e-5'
        if isinstance(value, bool):
            raise ValueError("a number, not a boolean")
        return value

    @model_validator(mode="before")
    @classmethod
    def _nest_number_format(cls, data: Any) -> Any:
        # a file lists the number format flat among the budgets: build the sub-record
        if not isinstance(data, dict):
            return data
        flat = {k: data[k] for k in NUMBER_FORMAT_FIELDS if k in data}
        if not flat:
            return data
        if "number_format" in data:
            raise ValueError(f"give the number format flat ({', '.join(flat)}) or as "
                             "'number_format', not both")
        return {**{k: v for k, v in data.items() if k not in flat}, "number_format": flat}

    @model_serializer(mode="wrap")
    def _flat_without_unset_optional_fields(self, handler):
        data = handler(self)
        if not isinstance(data, dict):
            return data
        if isinstance(data.get("number_format"), dict):  # absent: excluded from a partial dump
            flat = {**data.pop("number_format"), **data}
            # a field FILE_FIELDS lacks is still saved, last (tests/test_target_typed.py: none)
            order = [*FILE_FIELDS, *(k for k in flat if k not in FILE_FIELDS)]
            data = {k: flat[k] for k in order if k in flat}
        for key in OPTIONAL_FIELDS:
            if data.get(key) is None:
                data.pop(key, None)
        return data

    def model_copy(self, *, update: Mapping[str, Any] | None = None,
                   deep: bool = False) -> HardwareProfile:
        """A copy with ``update`` applied and validated (flat number-format fields allowed).

        Examples
        --------
        >>> from compiler.hardware import load_profile
        >>> load_profile("loihi").model_copy(update={"state_bits": 20}).number_format.state_bits
        20
        """
        if not update:
            return super().model_copy(deep=deep)
        return type(self).model_validate({**self.model_dump(), **update})

    @property
    def n_cores(self) -> int | None:
        """Cores available, ``cores_per_chip * chips`` (``None`` if either is unbounded)."""
        if self.cores_per_chip is None or self.chips is None:
            return None
        return self.cores_per_chip * self.chips

    def check_steps_per_frame(self, stages: Iterable[Mapping[str, Any]]) -> None:
        """Refuse a stage whose ``steps_per_frame`` exceeds :attr:`max_steps_per_frame`.

        Parameters
        ----------
        stages : iterable of dict
            The report's stage rows (:func:`compiler.report.stages.stage_rows`).

        Raises
        ------
        BudgetError
            Naming the stage, its network, its steps per frame and the limit.

        Examples
        --------
        >>> from compiler.hardware import load_profile
        >>> row = {"node": "f", "network": "n", "steps_per_frame": 357, "time_steps": 357,
        ...        "repetitions": 1, "multiplexed": False}
        >>> load_profile("loihi").check_steps_per_frame([row])  # no limit
        >>> tiny = load_profile("loihi").model_copy(update={"max_steps_per_frame": 100})
        >>> tiny.check_steps_per_frame([row])
        Traceback (most recent call last):
        ...
        ir.errors.BudgetError: stage 'f' of network 'n' runs 357 steps per frame (357 time \
steps), over max_steps_per_frame = 100 of loihi; use fewer time steps (option time_steps) \
or a target that runs more steps per frame
        """
        limit = self.max_steps_per_frame
        if limit is None:
            return
        for row in stages:
            steps = row["steps_per_frame"]
            if steps <= limit:
                continue
            how = (f"{row['time_steps']} time steps x {row['repetitions']} time-multiplexed "
                   "repetitions" if row["multiplexed"] else f"{row['time_steps']} time steps")
            fix = ("; use fewer time steps (option time_steps)"
                   + (", repetitions='spatial'" if row["multiplexed"] else "")
                   + " or a target that runs more steps per frame")
            raise BudgetError(f"stage {row['node']!r} of network {row['network']!r} runs "
                              f"{steps} steps per frame ({how}), over max_steps_per_frame = "
                              f"{limit} of {self.name}{fix}", node=row["node"])

    def limits(self) -> np.ndarray:
        """Per-core limits in :data:`BUDGETS` order as floats (``inf`` = unbounded).

        Examples
        --------
        >>> from compiler.hardware import load_profile
        >>> load_profile("loihi").limits().tolist()
        [1024.0, 4096.0, 4096.0, 1048576.0]
        """
        values = (self.neurons_per_core, self.input_axons_per_core,
                  self.output_axons_per_core, self.synapse_memory_bits_per_core)
        return np.array([np.inf if v is None else float(v) for v in values])


#: Fields a chip profile file must give (``null`` where unbounded) unless it says
#: ``unbounded: true``: every field but the name, the description and the optional fields.
REQUIRED_FIELDS: tuple[str, ...] = tuple(
    k for k in FILE_FIELDS if k not in ("name", "description", *OPTIONAL_FIELDS))

#: The target of a compile without one (``compile_graph(..., target=None)``): no budgets,
#: exact (floating-point) numbers, per-neuron scales and every neuron feature.  The lowering
#: reads it as it reads a chip; the allocation passes do not run.
NO_TARGET = HardwareProfile(name="ideal", per_neuron_scales=True,
                            description="no target: no budgets, exact numbers, every feature")
