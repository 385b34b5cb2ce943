"""Hardware profiles: the budgets of a neuromorphic chip as data (built-in YAML or a user file).

A :class:`HardwareProfile` lists what one core can hold and how many cores
there are.  The passes ``quantize``, ``split`` and ``place`` read nothing else
about the target, so a new chip is a new YAML file, never new code.  Budgets
given as ``null`` are unbounded.

A profile **file** gives every field of :data:`REQUIRED_FIELDS` (``null`` where a budget is
unbounded), so a field left out is an error, never a budget silently removed — unless the
file says ``unbounded: true``: then each field it leaves out is unbounded (``null``, or the
neutral format of :class:`HardwareProfile`'s defaults).  Counts and widths are integers
(not ``true``, not ``1.0``), switches are booleans, and rates and durations are numbers.

Examples
--------
>>> p = load_profile("loihi")
>>> p.neurons_per_core, p.n_cores, p.max_delay_steps
(1024, 128, 63)
>>> load_profile("unbounded").neurons_per_core is None
True
>>> _from_text("{name: mine, unbounded: true}", "file 'mine.yaml'").n_cores is None
True
>>> _from_text("{name: mine}", "file 'mine.yaml'")
Traceback (most recent call last):
...
ir.errors.CompileError: file 'mine.yaml': missing profile fields cores_per_chip, chips, \
neurons_per_core, input_axons_per_core, output_axons_per_core, synapse_memory_bits_per_core, \
bits_per_synapse, weight_bits, threshold_bits, weight_exponent_max, threshold_mantissa_bits, \
threshold_shift, bias_mantissa_bits, bias_exponent_max, state_bits, graded_spike_bits, \
per_neuron_scales, delay_bits, max_steps_per_frame, time_step_s, shared_weights_per_core, \
current_decay_offset_lsb, full_voltage_decay, reset, fire_once, threshold_schedule, \
input_gate, resonate_and_fire; give each (null = unbounded), or 'unbounded: true' to leave \
budgets out on purpose
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    Strict,
    ValidationError,
    field_validator,
    model_serializer,
)

from compiler.hardware.figures import EnergyFigures
from ir.errors import CompileError
from ir.model import short_repr
from ir.parsing import load_yaml
from ir.serialize import describe_yaml_error

__all__ = ["BOARD_FIELDS", "BUDGETS", "BUILTIN_BOARDS", "BUILTIN_PROFILES", "OPTIONAL_FIELDS",
           "REQUIRED_FIELDS", "HardwareProfile", "load_profile"]

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

_Int = Annotated[int, Strict()]  # not True, not 1.0: a count is an integer
_Count = _Int | None
_Bool = Annotated[bool, Strict()]  # not 1, not "yes"


class HardwareProfile(BaseModel):
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
    max_steps_per_frame : int or None
        Time steps one frame may use.
    time_step_s : float or None
        Wall-clock duration of one time step, s (for the latency estimate).
    shared_weights_per_core : bool
        Whether a core stores a shared matrix or stencil kernel once for all the
        neurons it holds, instead of once per neuron/repetition.
    current_decay_offset_lsb : int
        The current decay the chip adds to every ``du``, in ``1/4096`` per step (Loihi 1:
        1, so ``du = 0``, a non-leaking current, does not exist).
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

    name: str = Field(min_length=1)
    cores_per_chip: _Count = Field(default=None, ge=1)
    chips: _Count = Field(default=None, ge=1)
    neurons_per_core: _Count = Field(default=None, ge=1)
    input_axons_per_core: _Count = Field(default=None, ge=1)
    output_axons_per_core: _Count = Field(default=None, ge=1)
    synapse_memory_bits_per_core: _Count = Field(default=None, ge=1)
    bits_per_synapse: _Int = Field(default=64, ge=1)
    weight_bits: _Count = Field(default=None, ge=2, le=64)
    threshold_bits: _Count = Field(default=None, ge=2, le=64)
    weight_exponent_max: _Int = Field(default=0, ge=0, le=32)
    threshold_mantissa_bits: _Count = Field(default=None, ge=1, le=64)
    threshold_shift: _Int = Field(default=0, ge=0, le=32)
    bias_mantissa_bits: _Count = Field(default=None, ge=2, le=64)
    bias_exponent_max: _Int = Field(default=0, ge=0, le=32)
    state_bits: _Count = Field(default=None, ge=2, le=64)
    graded_spike_bits: _Count = Field(default=None, ge=2, le=64)
    per_neuron_scales: _Bool = False
    delay_bits: _Count = Field(default=None, ge=0, le=32)
    max_steps_per_frame: _Count = Field(default=None, ge=1)
    time_step_s: float | None = Field(default=None, gt=0)
    shared_weights_per_core: _Bool = False
    current_decay_offset_lsb: _Int = Field(default=0, ge=0, le=4096)
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

    @model_serializer(mode="wrap")
    def _without_unset_optional_fields(self, handler):
        data = handler(self)
        for key in OPTIONAL_FIELDS:
            if data.get(key) is None:
                data.pop(key, None)
        return data

    @property
    def n_cores(self) -> int | None:
        """Cores available, ``cores_per_chip * chips`` (``None`` if either is unbounded)."""
        if self.cores_per_chip is None or self.chips is None:
            return None
        return self.cores_per_chip * self.chips

    @property
    def max_delay_steps(self) -> int | None:
        """Largest synaptic delay, ``2**delay_bits - 1`` steps (``None``: unbounded)."""
        return None if self.delay_bits is None else (1 << self.delay_bits) - 1

    @property
    def threshold_max(self) -> int | None:
        """Largest threshold in state units (``None``: unbounded).

        Examples
        --------
        >>> load_profile("loihi").threshold_max  # 17-bit vth in 64-LSB state units
        131071
        """
        limits = []
        if self.threshold_bits is not None:
            limits.append((1 << (self.threshold_bits - 1)) - 1)
        if self.threshold_mantissa_bits is not None:
            limits.append(((1 << self.threshold_mantissa_bits) - 1) << self.threshold_shift)
        return min(limits) if limits else None

    def limits(self) -> np.ndarray:
        """Per-core limits in :data:`BUDGETS` order as floats (``inf`` = unbounded).

        Examples
        --------
        >>> load_profile("loihi").limits().tolist()
        [1024.0, 4096.0, 4096.0, 1048576.0]
        """
        values = (self.neurons_per_core, self.input_axons_per_core,
                  self.output_axons_per_core, self.synapse_memory_bits_per_core)
        return np.array([np.inf if v is None else float(v) for v in values])


#: Fields a chip profile file must give (``null`` where unbounded) unless it says
#: ``unbounded: true``: every field but the name, the description and the optional fields.
REQUIRED_FIELDS: tuple[str, ...] = tuple(
    k for k in HardwareProfile.model_fields if k not in ("name", "description",
                                                         *OPTIONAL_FIELDS))


def load_profile(target: str | Path | HardwareProfile | None) -> HardwareProfile:
    """A built-in profile by name, a profile from a YAML file, or ``unbounded`` for ``None``.

    Parameters
    ----------
    target : str, Path, HardwareProfile or None
        A name in :data:`BUILTIN_PROFILES`, or a path to a YAML file (a ``str``
        ending in ``.yaml``/``.yml`` counts as a path).

    Returns
    -------
    HardwareProfile

    Raises
    ------
    CompileError
        Unknown name, unreadable file, or a field out of range (naming the file and field).

    Examples
    --------
    >>> load_profile("spinnaker2").cores_per_chip
    152
    >>> b = load_profile("kapoho_point")
    >>> b.chip_profile, b.chips, b.n_cores, b.neurons_per_core
    ('loihi2', 8, 1024, 8192)
    >>> load_profile("tpu")
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: unknown hardware profile 'tpu'; built-in profiles are loihi, \
loihi2, spinnaker2, unbounded, boards kapoho_point, nahuku32, spinnaker2_48, hala_point, or \
give a path to a YAML profile file
    """
    if isinstance(target, HardwareProfile):
        return target
    if target is None:
        target = "unbounded"
    if isinstance(target, str) and target in BUILTIN_PROFILES:
        text = resources.files("compiler.hardware").joinpath(f"profiles/{target}.yaml")
        return _from_text(text.read_text(encoding="utf-8"), f"built-in profile {target!r}")
    if isinstance(target, str) and target in BUILTIN_BOARDS:
        text = resources.files("compiler.hardware").joinpath(f"boards/{target}.yaml")
        return _from_text(text.read_text(encoding="utf-8"), f"built-in board {target!r}")
    if not isinstance(target, str | Path):
        raise CompileError(f"hardware target must be a profile name, a YAML path or a "
                           f"HardwareProfile; got {type(target).__name__} {target!r}")
    path = Path(target)
    if not (isinstance(target, Path) or path.suffix in (".yaml", ".yml")):
        raise CompileError(f"unknown hardware profile {target!r}; built-in profiles are "
                           f"{', '.join(BUILTIN_PROFILES)}, boards {', '.join(BUILTIN_BOARDS)}, "
                           "or give a path to a YAML profile file")
    try:
        if not path.is_file() or path.stat().st_size > 1 << 20:  # not /dev/zero, not a giant
            raise CompileError(f"hardware profile file {str(path)!r} cannot be read: not a "
                               "regular file of at most 1 MiB")
        text = path.read_text(encoding="utf-8")
    except (OSError, ValueError) as err:  # UnicodeDecodeError; a NUL byte in the path
        raise CompileError(f"hardware profile file {str(path)!r} cannot be read: {err}") from err
    return _from_text(text, f"hardware profile file {str(path)!r}")


def _check_flag(data: dict, label: str) -> bool:
    """Pop the file's ``unbounded`` flag (a boolean; absent: false)."""
    flag = data.pop("unbounded", False)
    if not isinstance(flag, bool):
        raise CompileError(f"{label}: field 'unbounded' = {short_repr(flag)}: give true (leave "
                           "budgets out on purpose: each one left out is unbounded) or false")
    return flag


def _from_text(text: str, label: str) -> HardwareProfile:

    try:  # bounded: nesting, aliases expanded, duplicate keys (ir.parsing)
        data: Any = load_yaml(text, error=CompileError)
    except yaml.YAMLError as err:
        raise CompileError(f"{label}: not valid YAML: {describe_yaml_error(err)}") from err
    except CompileError as err:
        raise CompileError(f"{label}: {err}") from err
    if not isinstance(data, dict):
        raise CompileError(f"{label}: expected a mapping of profile fields, got "
                           f"{type(data).__name__}")
    board = data.get("chip_profile") is not None
    if board:  # a board: its chip's budgets, never loosened
        from compiler.hardware.boards import board_fields  # boards imports this module

        data = board_fields(data, label)
    else:
        data = dict(data)
        unbounded = _check_flag(data, label)
    try:  # model_validate: a non-string key is a field error, not a TypeError of **data
        profile = HardwareProfile.model_validate(data)
    except ValidationError as err:
        parts = [f"field '{'.'.join(map(str, e['loc']))}' = {short_repr(e.get('input'))}: "
                 f"{e['msg']}" for e in err.errors(include_url=False)]
        raise CompileError(f"{label}: " + "; ".join(parts)) from err
    missing = [] if board or unbounded else [k for k in REQUIRED_FIELDS if k not in data]
    if missing:  # after the fields' own checks: a misspelt field is named as such first
        raise CompileError(f"{label}: missing profile fields {', '.join(missing)}; give each "
                           "(null = unbounded), or 'unbounded: true' to leave budgets out on "
                           "purpose")
    return profile
