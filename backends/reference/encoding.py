r"""Input checking and spike trains of the source populations.

:func:`encode_inputs` checks ``simulate``'s inputs against the network's
encoders (ports, shapes, dtypes, finiteness, the codes' ranges under the policy
of :mod:`backends.reference.input_range`), splits signed/complex values onto
the ``part`` axis and returns one spike *train* per source population, built by
the encoder's code type through the registry :data:`~backends.reference.trains.TRAINS`
(:mod:`backends.reference.trains`: latency, stream and rate trains, re-exported here).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from backends.reference.input_range import DEFAULT_POLICY, check_policy, check_range
from backends.reference.trains import TRAINS, LatencyTrain, RateTrain, StreamTrain, Train
from compiler.snn.coding import N_PARTS, normalize_values, split_values
from compiler.snn.network import SpikingNetwork
from compiler.snn.stream import BIT_AXIS
from ir.errors import NetworkError, SimulationError

__all__ = ["LatencyTrain", "RateTrain", "StreamTrain", "TRAINS", "encode_inputs", "value_shape"]


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
