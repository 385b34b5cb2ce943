"""Neuromorphic targets: hardware profiles (data) and the per-core resource model.

:mod:`~compiler.hardware.profile` holds :class:`HardwareProfile` (its number
formats: :mod:`~compiler.hardware.number_format`), :mod:`~compiler.hardware.loading` reads
the built-in YAML profiles and a user's files (multi-chip boards:
:mod:`~compiler.hardware.boards`);
:mod:`~compiler.hardware.demand` counts what a block of neurons needs from a core
(neurons, fan-in and fan-out lines, synaptic memory);
:mod:`~compiler.hardware.repetition` finds the stages that can be time-multiplexed.
See ``docs/hardware.md``.
"""

from compiler.hardware.demand import Blocks, block_demand, stored_synapses
from compiler.hardware.loading import load_profile
from compiler.hardware.number_format import NumberFormat
from compiler.hardware.profile import (
    BUDGETS,
    BUILTIN_BOARDS,
    BUILTIN_PROFILES,
    NO_TARGET,
    HardwareProfile,
)

__all__ = [
    "BUDGETS",
    "BUILTIN_BOARDS",
    "BUILTIN_PROFILES",
    "Blocks",
    "HardwareProfile",
    "NO_TARGET",
    "NumberFormat",
    "block_demand",
    "load_profile",
    "stored_synapses",
]
