r"""Input checking and spike trains of the source populations.

:func:`encode_inputs` checks ``simulate``'s inputs against the network's
encoders (ports, shapes, dtypes, finiteness, the codes' ranges under the policy
of :mod:`backends.reference.input_range`), splits signed/complex values onto
the ``part`` axis and returns one spike *train* per source population, built by
the encoder's code type through the registry :data:`TRAINS`:

:class:`LatencyTrain`
    one spike per value at ``code.spike_steps(x)`` when that step is before the
    window end ``t_max`` (and before ``n_steps``).
:class:`StreamTrain`
    bit-plane spikes of a stream code (:mod:`compiler.snn.stream`): sample ``n`` of the
    streamed axis at step ``start_step + n``.
:class:`RateTrain`
    regular trains: a spike at step ``t`` iff
    ``floor((t+1)·r + φ) > floor(t·r + φ)`` (``code.spikes_at``), over all steps.

A train answers ``events_at(t)`` (flat indices into ``(frames, size)``,
ascending) for the step engine and ``all_events()`` for the closed form; both
evaluate the code's own functions, so the two engines see identical spikes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from backends.reference.input_range import DEFAULT_POLICY, check_policy, check_range
from backends.reference.order import events_of_first
from backends.reference.stream_levels import StreamLevels
from compiler.snn.coding import N_PARTS, LatencyCode, RateCode, normalize_values, split_values
from compiler.snn.network import SpikingNetwork
from compiler.snn.stream import BIT_AXIS, StreamCode
from ir.errors import NetworkError, SimulationError

__all__ = ["LatencyTrain", "RateTrain", "StreamTrain", "TRAINS", "encode_inputs", "value_shape"]

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


def value_shape(network: SpikingNetwork, port: str) -> tuple[int, ...]:
    """The shape of one frame of input ``port``: its population's, minus a split's part axis.

    Examples
    --------
    >>> from compiler.snn import Encoder, LatencyCode, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4,
    ...     populations=[Population(id="a", shape={"i": 3, "part": 2}, source=True)],
    ...     encoders=[Encoder(port="x", population="a", split="re_im",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
    >>> value_shape(net, "x")
    (3,)
    """
    enc = next(e for e in network.encoders if e.port == port)
    pop = network.population[enc.population]
    dims = pop.dims[:-1] if N_PARTS[enc.split] else pop.dims
    if enc.code.type == "stream":  # the bit axis stands where the streamed axis is
        i = pop.axes.index(BIT_AXIS)
        dims = (*dims[:i], enc.code.length, *dims[i + 1:])
    return dims


def encode_inputs(
    network: SpikingNetwork,
    inputs: Mapping[str, np.ndarray],
    trains: Mapping[str, Callable[..., Train]] = TRAINS,
    *,
    out_of_range: str | Mapping[str, str] = DEFAULT_POLICY,
    clipped: dict[str, int] | None = None,
) -> tuple[dict[str, Train], int, bool]:
    """Check ``inputs`` and turn them into one spike train per source population.

    Parameters
    ----------
    network : SpikingNetwork
        A validated network.
    inputs : mapping of port to array
        One array per encoder port, of the port's value shape, or with one
        leading frames axis (the same number of frames for every port).
    trains : mapping
        Train builder per code type (default :data:`TRAINS`).
    out_of_range : {"reject", "warn", "clip"} or mapping of port to it
        What to do with finite values outside a code's range
        (:mod:`backends.reference.input_range`): refuse them (default), clip them
        with an ``OutOfRangeWarning``, or clip them (per port with a mapping; ports
        it leaves out take the default, ``reject``).
    clipped : dict, optional
        Filled with the number of clipped values per port (``warn`` and ``clip``
        policies; a port without any is left out).

    Returns
    -------
    trains : dict
        Per source population id, its train.
    n_frames : int
        Frames in the batch (1 without a frames axis).
    framed : bool
        Whether the inputs had a leading frames axis.

    Raises
    ------
    SimulationError
        For missing or extra ports, a wrong shape, a non-numeric or complex
        array where the split is real, NaN/Inf (under every policy), values
        outside a code's range (``reject``), disagreeing frame counts, or an
        unknown policy.
    NetworkError
        If two encoders feed one population.

    Examples
    --------
    >>> from compiler.snn import Encoder, LatencyCode, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4,
    ...     populations=[Population(id="a", shape={"i": 2}, source=True)],
    ...     encoders=[Encoder(port="x", population="a",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
    >>> trains, n_frames, framed = encode_inputs(net, {"x": np.array([[1.0, 0.5]] * 3)})
    >>> n_frames, framed, [a.tolist() for a in trains["a"].all_events()]
    (3, True, [[0, 2, 4, 1, 3, 5], [0, 0, 0, 2, 2, 2]])
    """
    ports = {e.port: e for e in network.encoders}
    policies = {port: check_policy(out_of_range.get(port, DEFAULT_POLICY) if isinstance(
        out_of_range, Mapping) else out_of_range, f"network {network.name!r}") for port in ports}
    missing, extra = sorted(set(ports) - set(inputs)), sorted(set(inputs) - set(ports))
    if missing or extra:
        raise SimulationError(f"network {network.name!r}: inputs must be exactly the ports "
                              f"{sorted(ports)}; missing {missing}, unexpected {extra}")
    fed: dict[str, str] = {}
    frames: dict[str, int | None] = {}
    arrays = {}
    for port, enc in ports.items():
        if enc.population in fed:
            raise NetworkError(f"encoders {fed[enc.population]!r} and {port!r} both feed "
                               f"population {enc.population!r}; give each source one encoder",
                               node=port)
        fed[enc.population] = port
        arrays[port], frames[port] = _check_array(network, port, enc.split, inputs[port])
    counts = set(frames.values())
    if len(counts) > 1:
        raise SimulationError(f"network {network.name!r}: inputs disagree on the frames axis "
                              f"(None = no frames axis): {frames}; give every port the same "
                              "number of frames")
    n = counts.pop() if counts else None
    n_frames = 1 if n is None else n
    out = {}
    for port, enc in ports.items():
        x = arrays[port] if n is not None else arrays[port][None]
        x = normalize_values(x, _normalize_axes(network, enc))
        if (train := _signed_stream(enc, x, trains, network.n_steps)) is not None:
            out[enc.population] = train
            continue
        parts = split_values(x, enc.split)
        count = check_range(port, enc.code, parts, n_parts=N_PARTS[enc.split],
                            n_steps=network.n_steps, framed=n is not None,
                            policy="clip" if enc.saturate else policies[port], values=x,
                            split=enc.split)
        if count and clipped is not None:
            clipped[port] = count
        parts = parts.reshape(n_frames, -1)
        out[enc.population] = trains[enc.code.type](enc.code, parts, network.n_steps)
    return out, n_frames, n is not None


def _signed_stream(enc, x: np.ndarray, trains: Mapping, n_steps: int) -> StreamTrain | None:
    """The stream train of complex ``x`` straight from its components
    (:meth:`~compiler.snn.stream.StreamCode.signed_level_rows`) when no part is above the
    code's bound; None otherwise (out of range: the policy's path with the parts)."""
    code = enc.code
    if (enc.split != "re_im_signed" or code.type != "stream" or x.dtype != np.complex128
            or trains.get("stream") != StreamTrain.build or not x.size):
        return None
    x = np.ascontiguousarray(x)  # (a host op's output may be a strided view)
    comps = x.reshape(-1).view(np.float64)
    if max(comps.max(), -comps.min()) > code.bound():
        return None
    levels = code.signed_level_rows(x)
    return None if levels is None else StreamTrain.of_levels(code, levels, n_steps)


def _normalize_axes(network: SpikingNetwork, enc) -> tuple[int, ...]:
    """Indices (in ``(frames, *value_shape)``) of the encoder's ``normalize_axes``."""
    names = network.population[enc.population].axes
    names = names[:-1] if N_PARTS[enc.split] else names
    unknown = [a for a in enc.normalize_axes if a not in names]
    if unknown:
        raise NetworkError(f"encoder {enc.port!r}: normalize_axes {unknown} are not axes of its "
                           f"value {list(names)}; name value axes (not 'part')", node=enc.port)
    return tuple(1 + names.index(a) for a in enc.normalize_axes)


def _check_array(
    network: SpikingNetwork, port: str, split: str, value: object
) -> tuple[np.ndarray, int | None]:
    try:
        x = np.asarray(value)
    except (ValueError, TypeError) as err:  # ragged nested lists, objects numpy cannot hold
        raise SimulationError(f"input {port!r}: not an array ({err})", node=port) from None
    want = value_shape(network, port)
    if x.dtype.kind not in "biufc":  # not timedelta/datetime (numpy counts m8 as a number)
        raise SimulationError(f"input {port!r}: expected a numeric array, got dtype {x.dtype}",
                              node=port)
    if np.iscomplexobj(x) and split not in ("re_im", "re_im_signed"):
        raise SimulationError(f"input {port!r}: complex values need an encoder split 're_im' or "
                              f"'re_im_signed', but the split is {split!r}; pass the real part "
                              "or change the split", node=port)
    if x.shape == want:
        n = None
    elif x.ndim == len(want) + 1 and x.shape[1:] == want and x.shape[0] > 0:
        n = x.shape[0]
    else:
        raise SimulationError(f"input {port!r}: expected shape {want} or (n_frames, *{want}) "
                              f"with n_frames >= 1, got {x.shape}", node=port)
    if x.dtype.kind in "biu":
        return x, n
    with np.errstate(all="ignore"):  # (a sum past the range or of ±inf: the mask decides)
        if x.size and np.isfinite(np.sum(x)):
            return x, n  # a finite sum: every value finite (no mask built)
    bad = ~np.isfinite(x)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise SimulationError(f"input {port!r}: {int(bad.sum())} of {x.size} values are NaN or "
                              f"Inf, first at index {first}; NaN/Inf are refused under every "
                              "out_of_range policy: clean the input first (e.g. np.nan_to_num)",
                              node=port)
    return x, n
