"""Repetition plans of the ``split`` pass: which stages to time-multiplex, largest first.

The ``repetitions`` compile option (:data:`REPETITION_MODES`) chooses between
unrolling every repeated stage (``spatial``), multiplexing all that can be
(``temporal``) and trying plans with more and more of the
:func:`multiplex_candidates` multiplexed until the program fits (``auto``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from compiler.hardware import HardwareProfile
from compiler.hardware.repetition import Stage, stages
from compiler.snn import SpikingNetwork
from ir.errors import CompileError

__all__ = ["REPETITION_MODES", "multiplex_candidates", "plan", "repetition_mode"]

#: Values of the ``repetitions`` compile option.
REPETITION_MODES: tuple[str, ...] = ("auto", "spatial", "temporal")


def multiplex_candidates(networks: Sequence[SpikingNetwork], profile: HardwareProfile,
                         stage_lists: Sequence[list[Stage]] | None = None
                         ) -> list[tuple[int, Stage]]:
    """Multiplexable stages of all ``networks`` as ``(network index, stage)``, largest first.

    Size = the cores the stage's neurons and unshared synapse bits need at least
    (unbounded budgets count 0); ties: more repetitions first, then network order.

    Examples
    --------
    >>> from compiler.hardware import load_profile
    >>> from compiler.hardware.reference_networks import dft_network
    >>> [(k, s.key, s.repetitions) for k, s in multiplex_candidates([dft_network()],
    ...                                                            load_profile("loihi"))]
    [(0, 'rng', 256)]
    """
    limits = profile.limits()
    finite = np.where(np.isfinite(limits), limits, np.inf)
    found = []
    for k, sts in enumerate(stage_lists or [stages(n) for n in networks]):
        for i, st in enumerate(sts):
            if st.multiplexable:
                size = max(st.neurons / finite[0],
                           st.synapse_instances * profile.bits_per_synapse / finite[3])
                found.append((-size, -st.repetitions, k, i, st))
    return [(k, st) for *_, k, _, st in sorted(found, key=lambda f: f[:4])]


def repetition_mode(mode: str) -> str:
    """The ``repetitions`` option ``mode``, checked.

    Raises
    ------
    CompileError
        Not one of :data:`REPETITION_MODES`.
    """
    if mode not in REPETITION_MODES:
        raise CompileError(f"compile option 'repetitions' = {mode!r} is not one of "
                           f"{', '.join(REPETITION_MODES)}")
    return mode


def plan(networks, chosen: list[tuple[int, Stage]]) -> list[set[str]]:
    sets: list[set[str]] = [set() for _ in networks]
    for k, st in chosen:
        sets[k].add(st.key)
    return sets
