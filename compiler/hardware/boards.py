"""Multi-chip boards as profiles: a chip profile, a number of chips, and the chip-to-chip links.

A board file names its chip, a built-in chip profile (``chip_profile: loihi2``), and sets
only board fields:
``name``, ``description``, ``chips``, ``cores_per_chip`` (an integer, at most the chip's: a
board may expose fewer cores, never more), ``inter_chip_bandwidth_bit_s``,
``inter_chip_latency_s`` and ``spike_message_bits``; all but ``description`` and
``cores_per_chip`` are required (``null`` where a link figure is not given) unless the file
says ``unbounded: true``.  Every per-core budget and number format comes from the chip
profile unchanged, so a board can never loosen what one core holds.  The built-in boards
live in ``compiler/hardware/boards/*.yaml``, each figure commented with its source or
marked ``assumption``.

Examples
--------
>>> from compiler.hardware import load_profile
>>> b = load_profile("nahuku32")
>>> b.chip_profile, b.chips, b.cores_per_chip
('loihi', 32, 128)
>>> b.limits().tolist() == load_profile("loihi").limits().tolist()
True
>>> board_fields({"chip_profile": "loihi", "name": "x", "neurons_per_core": 4096}, "file 'x'")
Traceback (most recent call last):
...
ir.errors.CompileError: file 'x': a board takes its per-core budgets and formats from its chip \
profile 'loihi'; it cannot set neurons_per_core (board fields: name, description, chips, \
cores_per_chip, chip_profile, inter_chip_bandwidth_bit_s, inter_chip_latency_s, \
spike_message_bits, unbounded)
>>> board_fields({"chip_profile": "loihi", "name": "x", "chips": 2}, "file 'x'")
Traceback (most recent call last):
...
ir.errors.CompileError: file 'x': missing board fields inter_chip_bandwidth_bit_s, \
inter_chip_latency_s, spike_message_bits; give each (null = not given), or 'unbounded: true' to \
leave them out on purpose
"""

from __future__ import annotations

from compiler.hardware.loading import load_profile
from compiler.hardware.profile import BOARD_FIELDS, BUILTIN_PROFILES
from ir.errors import CompileError
from ir.model import short_repr

__all__ = ["BOARD_KEYS", "BOARD_REQUIRED", "board_fields"]

#: The keys a board file may set; everything else is its chip's.
BOARD_KEYS: tuple[str, ...] = ("name", "description", "chips", "cores_per_chip", *BOARD_FIELDS,
                               "unbounded")
#: The keys a board file must give (``cores_per_chip`` defaults to the chip's), unless it says
#: ``unbounded: true`` (then a link field left out is not given).
BOARD_REQUIRED: tuple[str, ...] = ("chips", *BOARD_FIELDS[1:])


def board_fields(data: dict, label: str) -> dict:
    """The full profile fields of a board: its chip profile's, updated by the board's keys.

    Parameters
    ----------
    data : dict
        The board file's mapping (with ``chip_profile``).
    label : str
        Names the file in errors.

    Returns
    -------
    dict
        Fields for :class:`~compiler.hardware.HardwareProfile`.

    Raises
    ------
    CompileError
        The chip profile is not a built-in chip (a board, ``unbounded``, a file), the board
        sets a per-core field, or it gives more cores per chip than the chip has.
    """
    chip_name = data["chip_profile"]
    chips = [c for c in BUILTIN_PROFILES if c != "unbounded"]
    if not isinstance(chip_name, str) or chip_name not in chips:
        raise CompileError(f"{label}: 'chip_profile' must name a built-in chip profile "
                           f"({', '.join(chips)}; not a board), got {short_repr(chip_name)}")
    chip = load_profile(chip_name)
    extra = [k for k in data if k not in BOARD_KEYS]
    if extra:
        raise CompileError(
            f"{label}: a board takes its per-core budgets and formats from its chip profile "
            f"{chip_name!r}; it cannot set {', '.join(map(str, extra))} (board fields: "
            f"{', '.join(BOARD_KEYS)})")
    data = dict(data)
    flag = data.pop("unbounded", False)
    if not isinstance(flag, bool):
        raise CompileError(f"{label}: field 'unbounded' = {short_repr(flag)}: give true or false")
    cpc = data.get("cores_per_chip", chip.cores_per_chip)
    if isinstance(cpc, bool) or not isinstance(cpc, int) or cpc < 1:
        raise CompileError(f"{label}: field 'cores_per_chip' = {short_repr(cpc)}: give an "
                           f"integer in 1..{chip.cores_per_chip} (the cores of one {chip_name} "
                           "chip)")
    if cpc > chip.cores_per_chip:
        raise CompileError(f"{label}: cores_per_chip = {cpc!r} exceeds the {chip.cores_per_chip} "
                           f"cores of one {chip_name} chip; a board cannot add cores to a chip")
    missing = [k for k in BOARD_REQUIRED if k not in data]
    if missing and not flag:
        raise CompileError(f"{label}: missing board fields {', '.join(missing)}; give each "
                           "(null = not given), or 'unbounded: true' to leave them out on "
                           "purpose")
    return {**chip.model_dump(), **data}
