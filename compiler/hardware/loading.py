"""Loading a hardware profile: a built-in name, a board, or a user's YAML file.

A profile **file** gives every field of :data:`~compiler.hardware.profile.REQUIRED_FIELDS`
(``null`` where a budget is unbounded), so a field left out is an error, never a budget
silently removed — unless the file says ``unbounded: true``: then each field it leaves out
is unbounded (``null``, or the neutral format of
:class:`~compiler.hardware.HardwareProfile`'s defaults).  The file lists the number
format's fields flat among the budgets (:data:`~compiler.hardware.profile.FILE_FIELDS`).
Counts and widths are integers (not ``true``, not ``1.0``), switches are booleans, and
rates and durations are numbers.

Examples
--------
>>> p = load_profile("loihi")
>>> p.neurons_per_core, p.n_cores, p.number_format.max_delay_steps
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

from pydantic import ValidationError

from compiler.hardware.number_format import NUMBER_FORMAT_FIELDS
from compiler.hardware.profile import (
    BUILTIN_BOARDS,
    BUILTIN_PROFILES,
    REQUIRED_FIELDS,
    HardwareProfile,
)
from ir.errors import CompileError
from ir.model import short_repr
from ir.serialize import load_yaml_mapping

__all__ = ["load_profile"]


def load_profile(target: str | Path | HardwareProfile) -> HardwareProfile:
    """A built-in profile or board by name, or a profile from a YAML file (a profile: itself).

    Parameters
    ----------
    target : str, Path or HardwareProfile
        A name in :data:`~compiler.hardware.profile.BUILTIN_PROFILES` or
        :data:`~compiler.hardware.profile.BUILTIN_BOARDS` (``unbounded``: no budgets), or a
        path to a YAML file (a ``str`` ending in ``.yaml``/``.yml`` counts as a path).
        ``None`` is refused: it is no profile (a compile without a target is
        ``compile_graph(..., target=None)``).

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
    >>> load_profile(None)
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: hardware target must be a profile name, a YAML path or a \
HardwareProfile; got NoneType None
    >>> load_profile("tpu")
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: unknown hardware profile 'tpu'; built-in profiles are loihi, \
loihi2, spinnaker2, unbounded, boards kapoho_point, nahuku32, spinnaker2_48, hala_point, or \
give a path to a YAML profile file
    """
    if isinstance(target, HardwareProfile):
        return target
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

    # bounded: nesting, aliases expanded, duplicate keys (ir.parsing)
    data = load_yaml_mapping(text, label, "profile fields", error=CompileError)
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
        parts = [f"field '{_field_name(e['loc'])}' = {short_repr(e.get('input'))}: "
                 f"{e['msg']}" for e in err.errors(include_url=False)]
        raise CompileError(f"{label}: " + "; ".join(parts)) from err
    missing = [] if board or unbounded else [k for k in REQUIRED_FIELDS if k not in data]
    if missing:  # after the fields' own checks: a misspelt field is named as such first
        raise CompileError(f"{label}: missing profile fields {', '.join(missing)}; give each "
                           "(null = unbounded), or 'unbounded: true' to leave budgets out on "
                           "purpose")
    return profile


def _field_name(loc: tuple) -> str:
    """A validation error's field as the file spells it (the number format's flat)."""
    if len(loc) > 1 and loc[0] == "number_format" and loc[1] in NUMBER_FORMAT_FIELDS:
        loc = loc[1:]
    return ".".join(map(str, loc))
