"""What a simulation returns: :class:`SimResult`, and the engines' raw record :class:`Activity`."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Activity", "LazyArrays", "SimResult", "first_step_dtype", "first_steps"]


def first_step_dtype(n_steps: int) -> np.dtype:
    """The smallest signed integer type that holds the step count ``n_steps`` (so every step
    ``0 .. n_steps − 1``) and the "never" sentinel ``−1``: the dtype of
    :attr:`SimResult.first_spike_steps`.

    A frame's first-spike steps are as many as its neurons (three populations of half a
    million for a carrada chain); stored as ``int16`` they take a quarter of ``int64``'s
    bytes, written and paged in once per frame.

    Examples
    --------
    >>> [first_step_dtype(n).name for n in (100, 128, 768, 40_000)]
    ['int8', 'int16', 'int16', 'int32']
    """
    for dtype in (np.int8, np.int16, np.int32):
        if n_steps <= np.iinfo(dtype).max:
            return np.dtype(dtype)
    return np.dtype(np.int64)


def first_steps(first: np.ndarray, n_steps: int, shape: tuple[int, ...]) -> np.ndarray:
    """An engine's ``int64`` first-spike steps as :attr:`SimResult.first_spike_steps`:
    ``shape``, in :func:`first_step_dtype` (every value a step or ``−1``, so the cast is
    exact).

    Examples
    --------
    >>> steps = first_steps(np.array([3, -1]), 8, (1, 2))
    >>> steps.tolist(), steps.dtype
    ([[3, -1]], dtype('int8'))
    """
    return np.asarray(first).reshape(shape).astype(first_step_dtype(n_steps), copy=False)


class LazyArrays(Mapping):
    """A read-only mapping whose values are arrays or zero-argument functions computing them;
    a function is called on first access and its array kept (values nobody reads, such as a
    stream source's per-neuron first spikes, cost nothing).  Copied and pickled as a plain
    dict of arrays.

    Examples
    --------
    >>> calls = []
    >>> m = LazyArrays({"a": np.zeros(2), "b": lambda: calls.append(1) or np.ones(3)})
    >>> sorted(m), calls
    (['a', 'b'], [])
    >>> m["b"].tolist(), m["b"].shape, calls
    ([1.0, 1.0, 1.0], (3,), [1])
    >>> import copy
    >>> type(copy.deepcopy(m)).__name__  # copied (and sent to a worker process) as a dict
    'dict'
    """

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, np.ndarray | Callable[[], np.ndarray]]) -> None:
        self._values = dict(values)

    def __getitem__(self, key: str) -> np.ndarray:
        value = self._values[key]
        if callable(value):
            value = self._values[key] = value()
        return value

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __reduce__(self):
        return dict, (dict(self.items()),)

    def __repr__(self) -> str:
        return f"LazyArrays({sorted(self._values)})"


@dataclass(frozen=True, eq=False)
class Activity:
    """The raw record both engines produce (flat per-neuron arrays, frames first).

    Attributes
    ----------
    first_spike : dict
        Per population, ``(n_frames, size)`` int64 first spike step, ``-1`` = never.
    counts : dict
        Per population, ``(n_frames, size)`` spikes per neuron in the frame: int64, or bool
        where a neuron spikes at most once (the closed form's fire-once and latency
        populations: its fired mask, not copied to int64).
    membrane : dict
        Per neuron population, ``(n_frames, size)`` membrane ``v`` after the last step.
    synaptic_events : dict
        Per projection, spikes delivered × synapses reached (over the batch).
    rasters : dict or None
        Per population, ``(n_frames, n_steps, size)`` bool spikes, when recorded.
    overflow : dict
        Per population, neuron-steps with ``u`` or ``v`` beyond the chip's state range
        (the step engine; populations without any left out).
    totals : dict
        Per population, its spikes summed, where known without its per-neuron ``counts``
        (which may then be computed on demand, :class:`LazyArrays`).
    """

    first_spike: dict[str, np.ndarray]
    counts: dict[str, np.ndarray]
    membrane: dict[str, np.ndarray]
    synaptic_events: dict[str, int]
    rasters: dict[str, np.ndarray] | None = None
    overflow: dict[str, int] = field(default_factory=dict)
    totals: dict[str, int] = field(default_factory=dict)

    def spike_totals(self) -> dict[str, int]:
        """Spikes per population over the batch (``totals``, else the counts summed)."""
        return {pid: self.totals[pid] if pid in self.totals else int(self.counts[pid].sum())
                for pid in self.counts}


@dataclass(frozen=True, eq=False)
class SimResult:
    """The outcome of :func:`backends.reference.simulate`.

    Attributes
    ----------
    outputs : dict of str to ndarray
        Decoded values per output port (after ``combine``); a leading frames
        axis iff the inputs had one.
    spike_counts : dict of str to int
        Spikes per population (sources included), summed over the batch.
    synaptic_events : dict of str to int
        Per projection, spikes delivered within the frame × synapses each reaches
        (the work a chip does; counted whether or not the target's input is on).
    first_spike_steps : dict of str to ndarray
        Per population, ``(n_frames, *shape)`` first spike step, ``-1`` = never, in the
        smallest signed integer type that holds ``n_steps`` and ``-1``
        (:func:`first_step_dtype`: ``int8`` up to 127 steps, ``int16`` up to 32767).
    spikes : dict of str to ndarray or None
        Per population, bool rasters ``(n_frames, n_steps, *shape)`` when
        ``record_spikes=True``.
    mode : {"step", "closed"}
        The engine that ran (``auto`` resolved).
    arithmetic : {"float64", "int64"}
        The arithmetic used.
    n_steps, n_frames : int
        Steps per frame and frames in the batch.
    clipped : dict of str to int
        Per input port, how many values were outside the encoder's range and
        clipped (``out_of_range="clip"``; ports without any are left out).
    state_overflow : dict of str to int
        Per population, neuron-steps whose ``u`` or ``v`` left the chip's state range
        ``±(2^(state_bits−1) − 1)`` (a network quantized for a target with
        ``state_bits``): there the chip's ``u`` wraps and its ``v`` saturates (and a
        saturated ``v`` fires) while this engine computes wider. The step engine counts
        every step; the closed form counts the final membranes only (a lower bound).
    """

    outputs: dict[str, np.ndarray]
    spike_counts: dict[str, int]
    synaptic_events: dict[str, int]
    first_spike_steps: dict[str, np.ndarray]
    spikes: dict[str, np.ndarray] | None
    mode: str
    arithmetic: str
    n_steps: int
    n_frames: int
    clipped: dict[str, int] = field(default_factory=dict)
    state_overflow: dict[str, int] = field(default_factory=dict)

    @property
    def total_spikes(self) -> int:
        """Spikes of every population, summed."""
        return sum(self.spike_counts.values())

    @property
    def total_synaptic_events(self) -> int:
        """Synaptic events of every projection, summed."""
        return sum(self.synaptic_events.values())

    def summary(self) -> str:
        """A short human-readable report of the run.

        Examples
        --------
        >>> r = SimResult(outputs={"y": np.zeros(2)}, spike_counts={"a": 3},
        ...               synaptic_events={"w": 6}, first_spike_steps={}, spikes=None,
        ...               mode="step", arithmetic="float64", n_steps=8, n_frames=1)
        >>> print(r.summary())
        mode=step arithmetic=float64 frames=1 steps=8 spikes=3 synaptic_events=6
          population a: 3 spikes
          projection w: 6 synaptic events
          output y: shape (2,)
        """
        lines = [f"mode={self.mode} arithmetic={self.arithmetic} frames={self.n_frames} "
                 f"steps={self.n_steps} spikes={self.total_spikes} "
                 f"synaptic_events={self.total_synaptic_events}"]
        lines += [f"  population {k}: {v} spikes" for k, v in self.spike_counts.items()]
        lines += [f"  projection {k}: {v} synaptic events" for k, v in self.synaptic_events.items()]
        lines += [f"  output {k}: shape {v.shape}" for k, v in self.outputs.items()]
        lines += [f"  input {k}: {v} values outside the encoder's range, clipped"
                  for k, v in self.clipped.items()]
        lines += [f"  population {k}: {v} neuron-steps beyond the chip's state range"
                  for k, v in self.state_overflow.items()]
        return "\n".join(lines)

    @classmethod
    def stack(cls, results: list[SimResult]) -> SimResult:
        """The results of single-frame runs of one network as one batch of those frames.

        Outputs, first-spike steps and rasters are stacked frame after frame, counts
        summed: what one batched :func:`~backends.reference.simulate` call returns.

        Examples
        --------
        >>> r = SimResult(outputs={"y": np.zeros(2)}, spike_counts={"a": 3},
        ...               synaptic_events={"w": 6}, first_spike_steps={"a": np.zeros((1, 2))},
        ...               spikes=None, mode="step", arithmetic="float64", n_steps=8, n_frames=1)
        >>> both = SimResult.stack([r, r])
        >>> both.outputs["y"].shape, both.spike_counts, both.first_spike_steps["a"].shape
        ((2, 2), {'a': 6}, (2, 2))
        """
        first = results[0]

        def total(name: str) -> dict[str, int]:
            keys = dict.fromkeys(k for r in results for k in getattr(r, name))
            return {k: sum(getattr(r, name).get(k, 0) for r in results) for k in keys}

        return cls(
            outputs={k: np.stack([r.outputs[k] for r in results]) for k in first.outputs},
            spike_counts=total("spike_counts"), synaptic_events=total("synaptic_events"),
            first_spike_steps={k: np.concatenate([r.first_spike_steps[k] for r in results])
                               for k in first.first_spike_steps},
            spikes=None if first.spikes is None else {
                k: np.concatenate([r.spikes[k] for r in results]) for k in first.spikes},
            mode="+".join(dict.fromkeys(r.mode for r in results)), arithmetic=first.arithmetic,
            n_steps=first.n_steps, n_frames=sum(r.n_frames for r in results),
            clipped={k: v for k, v in total("clipped").items() if v},
            state_overflow={k: v for k, v in total("state_overflow").items() if v})
