"""Neuromorphic targets: hardware profiles (data) and the per-core resource model.

:mod:`~compiler.hardware.profile` holds :class:`HardwareProfile` and the
built-in YAML profiles (multi-chip boards: :mod:`~compiler.hardware.boards`);
:mod:`~compiler.hardware.demand` counts what a block of neurons needs from a core
(neurons, fan-in and fan-out lines, synaptic memory);
:mod:`~compiler.hardware.repetition` finds the stages that can be time-multiplexed.
See ``docs/hardware.md``.
"""

from compiler.hardware.demand import Blocks, block_demand, stored_synapses
from compiler.hardware.profile import (
    BUDGETS,
    BUILTIN_BOARDS,
    BUILTIN_PROFILES,
    HardwareProfile,
    load_profile,
)

__all__ = [
    "BUDGETS",
    "BUILTIN_BOARDS",
    "BUILTIN_PROFILES",
    "Blocks",
    "HardwareProfile",
    "block_demand",
    "load_profile",
    "stored_synapses",
]
