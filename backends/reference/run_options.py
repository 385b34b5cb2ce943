"""One record of how to run: engine, arithmetic, rasters, out-of-range policy, resource limits.

:func:`backends.reference.simulate` runs one :class:`~compiler.snn.SpikingNetwork`;
:func:`backends.reference.run_program` runs a whole compiled program and calls
``simulate`` for each spiking segment.  Both take the same :class:`RunOptions`
(``options=``), or its fields as keyword arguments; the program passes its record
on to every segment (with the per-port policy a decoded upstream value needs).

Examples
--------
>>> RunOptions(mode="closed").checked("network 'n'").mode
'closed'
>>> RunOptions(mode="fast").checked("network 'n'")
Traceback (most recent call last):
...
ir.errors.SimulationError: network 'n': mode 'fast' is not one of ('step', 'closed', 'auto')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from backends.reference.guards import MAX_MEMORY_BYTES, MAX_TIME_S
from backends.reference.input_range import DEFAULT_POLICY
from ir.errors import SimulationError
from ir.limits import check_limit

__all__ = ["ARITHMETICS", "ENGINE_MODES", "MODES", "PARALLEL", "RunOptions", "check_workers"]

#: The engines of :func:`~backends.reference.simulate` (its ``ENGINES`` has these keys).
ENGINE_MODES = ("step", "closed")
#: The run modes: an engine, or ``auto`` (closed form where the network is eligible, else
#: step).  Every list of modes (the CLI's choices, the sweep spec's) is this one.
MODES = (*ENGINE_MODES, "auto")
#: Number types of currents and membranes.
ARITHMETICS = ("float64", "int64")
#: What the workers of a frames axis are (:attr:`RunOptions.parallel`).
PARALLEL = ("auto", "threads", "processes")


@dataclass(frozen=True)
class RunOptions:
    """How a network or a program runs.

    Attributes
    ----------
    mode : {"step", "closed", "auto"}
        ``step`` runs every time step; ``closed`` computes the spike steps of a
        fire-once feed-forward network directly; ``auto`` picks ``closed`` when eligible.
    arithmetic : {"float64", "int64"}
        ``int64`` is fixed point with truncating decays (integer parameters).
    record_spikes : bool
        Keep full spike rasters.
    out_of_range : {"reject", "warn", "clip"} or mapping of port to it
        Input values above an encoder's range (:mod:`backends.reference.input_range`).
    max_memory_bytes, max_time_s : int, float or None
        Refuse a run whose estimate exceeds them (:mod:`backends.reference.guards`).
    workers : int or None
        Workers that share out the frames of a program run over a frames axis
        (:mod:`backends.reference.frames_run`; the result is the same, bit for bit, for
        any number); None: one per core the process may use.  A single frame, and
        :func:`~backends.reference.simulate` (which batches its frames itself), run on
        the calling thread.
    parallel : {"auto", "threads", "processes"}
        What the workers are: threads of this process, or worker processes forked once
        and kept for the program's next runs, which exchange frames through shared
        memory (:mod:`backends.reference.frames_pool`; threads where the system cannot
        fork).  ``auto`` (the default) takes processes where forking is safe — no other
        thread runs in this process — and threads otherwise
        (:func:`~backends.reference.frames_run.resolve_parallel`): a frame keeps the
        interpreter lock for part of its time, which threads cannot share.
    """

    mode: str = "auto"
    arithmetic: str = "float64"
    record_spikes: bool = False
    out_of_range: str | Mapping[str, str] = DEFAULT_POLICY
    max_memory_bytes: int | None = MAX_MEMORY_BYTES
    max_time_s: float | None = MAX_TIME_S
    workers: int | None = None
    parallel: Literal["auto", "threads", "processes"] = "auto"

    def checked(self, where: str) -> RunOptions:
        """This record, its engine, arithmetic and limits checked (errors name ``where``).

        Raises
        ------
        SimulationError
            An unknown mode or arithmetic, a limit that is not a positive finite
            number or None, or ``workers`` that is not a whole number >= 1 or None.
        """
        if not isinstance(self.mode, str) or self.mode not in MODES:
            raise SimulationError(f"{where}: mode {self.mode!r} is not one of {MODES}")
        if not isinstance(self.arithmetic, str) or self.arithmetic not in ARITHMETICS:
            raise SimulationError(f"{where}: arithmetic {self.arithmetic!r} is not one of "
                                  f"{ARITHMETICS}")
        check_limit("max_memory_bytes", self.max_memory_bytes, "bytes", where=where)
        check_limit("max_time_s", self.max_time_s, "s", where=where)
        check_workers(self.workers, where)
        if not isinstance(self.parallel, str) or self.parallel not in PARALLEL:
            raise SimulationError(f"{where}: parallel={self.parallel!r} is not one of "
                                  f"{PARALLEL}")
        return self


def check_workers(workers: object, where: str) -> int | None:
    """``workers`` if it is None or a whole number >= 1, else a :class:`SimulationError`.

    Examples
    --------
    >>> check_workers(2, "program 'p'"), check_workers(None, "program 'p'")
    (2, None)
    >>> check_workers(0, "program 'p'")
    Traceback (most recent call last):
    ...
    ir.errors.SimulationError: program 'p': workers=0 must be a whole number >= 1 (threads \
for a frames axis) or None (one per core)
    """
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int | np.integer) or workers < 1:
        raise SimulationError(f"{where}: workers={workers!r} must be a whole number >= 1 "
                              "(threads for a frames axis) or None (one per core)")
    return int(workers)
