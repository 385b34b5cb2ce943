r"""The spike trains of the source populations, one class per code type.

:func:`~backends.reference.encoding.encode_inputs` builds one train per source population
through the registry :data:`TRAINS` (by the encoder's code ``type``):

:class:`LatencyTrain`
    one spike per value at ``code.spike_steps(x)`` when that step is before the
    window end ``t_max`` (and before ``n_steps``).
:class:`StreamTrain`
    bit-plane spikes of a stream code (:mod:`compiler.snn.stream`): sample ``n`` of the
    streamed axis at step ``start_step + n``, kept as the samples' levels
    (:mod:`backends.reference.stream_levels`).
:class:`RateTrain`
    regular trains: a spike at step ``t`` iff
    ``floor((t+1)·r + φ) > floor(t·r + φ)`` (``code.spikes_at``), over all steps.

A train answers ``events_at(t)`` (flat indices into ``(frames, size)``,
ascending) for the step engine and ``all_events()`` for the closed form; both
evaluate the code's own functions, so the two engines see identical spikes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from backends.reference.order import events_of_first
from backends.reference.stream_levels import StreamLevels
from compiler.snn.coding import LatencyCode, RateCode
from compiler.snn.stream import StreamCode

__all__ = ["LatencyTrain", "RateTrain", "StreamTrain", "TRAINS", "Train"]

#: Values per chunk of a rate train's event listing.
_CHUNK_ELEMENTS = 1 << 22


@dataclass(frozen=True, eq=False)
class LatencyTrain:
    """At most one spike per source neuron, at its encoded step.

    ``first`` holds each neuron's step (``-1``: none); the events ordered by step, which
    the step engine reads, are sorted once on first use (the closed form's silent spans
    read ``first`` directly).

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import LatencyCode
    >>> tr = LatencyTrain.build(LatencyCode(t_max=4, x_min=0.0, x_max=1.0),
    ...                         np.array([[1.0, 0.5, 0.0]]), n_steps=8)
    >>> tr.first.tolist(), tr.events_at(0).tolist(), tr.events_at(2).tolist()
    ([0, 2, -1], [0], [1])
    >>> [a.tolist() for a in tr.all_events()]
    [[0, 1], [0, 2]]
    """

    first: np.ndarray
    n_steps: int
    #: Each neuron spikes at most once (the step engine then keeps first spikes only).
    at_most_once: ClassVar[bool] = True

    @classmethod
    def build(cls, code: LatencyCode, values: np.ndarray, n_steps: int) -> LatencyTrain:
        """Spike steps of ``values`` (shape ``(frames, size)``) under ``code``."""
        steps = code.spike_steps(values).ravel()
        steps[steps >= min(code.t_max, n_steps)] = -1
        return cls(steps, n_steps)

    @cached_property
    def _sorted(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(flat, steps, bounds)``: events stable by step (ties by index), step bounds."""
        flat, steps = events_of_first(self.first, self.n_steps)
        return flat, steps, np.searchsorted(steps, np.arange(self.n_steps + 1))

    def events_at(self, t: int) -> np.ndarray:
        """Flat indices of the neurons spiking at step ``t``, ascending."""
        flat, _, bounds = self._sorted
        return flat[bounds[t]:bounds[t + 1]]

    def all_events(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, step)`` of every spike in the frame."""
        flat, steps, _ = self._sorted
        return flat, steps


@dataclass(frozen=True, eq=False)
class RateTrain:
    """Regular spike trains with the code's deterministic phase.

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import RateCode
    >>> tr = RateTrain.build(RateCode(max_rate=0.5), np.array([[1.0, 0.5]]), n_steps=4)
    >>> [tr.events_at(t).tolist() for t in range(4)]
    [[], [0], [], [0, 1]]
    """

    code: RateCode
    rates: np.ndarray
    n_steps: int
    #: Neurons may spike many times.
    at_most_once: ClassVar[bool] = False

    @classmethod
    def build(cls, code: RateCode, values: np.ndarray, n_steps: int) -> RateTrain:
        """Rates of ``values`` (shape ``(frames, size)``) under ``code``."""
        return cls(code, code.rates(values).ravel(), n_steps)

    def events_at(self, t: int) -> np.ndarray:
        """Flat indices of the neurons spiking at step ``t``, ascending."""
        return np.flatnonzero(self.code.spikes_at(self.rates, t))

    def all_events(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, step)`` of every spike in the frame, ordered by step then index."""
        chunk = max(1, _CHUNK_ELEMENTS // max(1, self.rates.size))
        flats, steps = [], []
        for t0 in range(0, self.n_steps, chunk):
            t = np.arange(t0, min(t0 + chunk, self.n_steps))[:, None]
            st, fl = np.nonzero(self.code.spikes_at(self.rates[None, :], t))
            flats.append(fl)
            steps.append(st + t0)
        return np.concatenate(flats), np.concatenate(steps).astype(np.int64)


@dataclass(frozen=True, eq=False)
class StreamTrain:
    """Bit-plane spikes of a stream code: sample ``n`` at step ``start_step + n``.

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn.stream import StreamCode
    >>> code = StreamCode(axis="n", length=2, inner=1, bits=2, x_max=3.0, start_step=1)
    >>> tr = StreamTrain.build(code, np.array([[3.0, 2.0]]), n_steps=4)
    >>> [tr.events_at(t).tolist() for t in range(4)], [a.tolist() for a in tr.all_events()]
    ([[], [0, 1], [1], []], [[0, 1, 1], [1, 1, 2]])
    """

    #: The levels, row ``n`` sent at step ``start_step + n`` (cut at ``n_steps``).
    stream: StreamLevels
    #: Bit neurons spike once per sample whose bit is set.
    at_most_once: ClassVar[bool] = False

    @classmethod
    def build(cls, code: StreamCode, values: np.ndarray, n_steps: int) -> StreamTrain:
        """Levels of ``values`` (shape ``(frames, size)``), cut at ``n_steps``."""
        return cls.of_levels(code, code.level_rows(values), n_steps)

    @classmethod
    def of_levels(cls, code: StreamCode, levels: np.ndarray, n_steps: int) -> StreamTrain:
        """The train of ``code``'s level rows ``levels``, cut at ``n_steps``."""
        levels = levels[:max(0, n_steps - code.start_step)]
        return cls(StreamLevels(levels, code.bits, code.start_step))

    @property
    def start(self) -> int:
        """The step of row 0."""
        return self.stream.start

    @property
    def planes(self) -> np.ndarray:
        """``(rows, frames·size)`` boolean spikes per streamed index (built once)."""
        return self.stream.raster()[0]

    def events_at(self, t: int) -> np.ndarray:
        """Flat indices of the neurons spiking at step ``t``, ascending."""
        n = t - self.start
        if 0 <= n < len(self.planes):
            return np.flatnonzero(self.planes[n])
        return np.zeros(0, np.int64)

    def all_events(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, step)`` of every spike in the frame, ordered by step then index."""
        n, flat = np.nonzero(self.planes)
        return flat.astype(np.int64), (n + self.start).astype(np.int64)


Train = LatencyTrain | RateTrain | StreamTrain

#: Spike-train builders by code ``type``.
TRAINS: dict[str, Callable[..., Train]] = {"latency": LatencyTrain.build, "rate": RateTrain.build,
                                           "stream": StreamTrain.build}
