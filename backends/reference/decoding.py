r"""Output decoding: from a population's activity to the values of an output port.

Per neuron, by the decoder's ``kind`` (registry :data:`DECODERS`):

==============  ===========================================================
``spike_time``  ``scale·(t_ref − t_s) + offset`` at the first spike step
                ``t_s``; ``missing`` where the neuron never fired
``count``       ``scale·count + offset``
``membrane``    ``scale·v + offset`` with ``v`` after the last step
``spiked``      ``1.0`` where the neuron fired, else ``0.0``
``spike_table`` ``scale·table[t_s − t_ref] + offset``; ``missing`` otherwise
==============  ===========================================================

A decoder with per-index gains (``gain_axis``, ``gains``) divides every value but
``missing`` by the gain of the neuron's index along that axis,
``y ← y / gains[i]`` (the network carried ``gains[i]·y``), then
:func:`~compiler.snn.combine_parts` folds the trailing ``part`` axis.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import lru_cache

import numpy as np

from backends.reference.result import Activity
from compiler.snn.coding import N_PARTS, Decoder, combine_parts
from compiler.snn.network import PART_AXIS, SpikingNetwork
from ir.errors import NetworkError

__all__ = ["DECODERS", "decode_outputs", "check_decoders"]


def _spike_time(dec: Decoder, act: Activity, pid: str, gains: np.ndarray | float) -> np.ndarray:
    t = act.first_spike[pid]
    value = (dec.scale * (dec.t_ref - t.astype(np.float64)) + dec.offset) / gains
    return np.where(t >= 0, value, dec.missing)


def _count(dec: Decoder, act: Activity, pid: str, gains: np.ndarray | float) -> np.ndarray:
    return (dec.scale * act.counts[pid].astype(np.float64) + dec.offset) / gains


def _membrane(dec: Decoder, act: Activity, pid: str, gains: np.ndarray | float) -> np.ndarray:
    y = np.multiply(act.membrane[pid], dec.scale, dtype=np.float64)  # one buffer, in place
    np.add(y, dec.offset, out=y)
    return np.divide(y, gains, out=y)


def _spiked(dec: Decoder, act: Activity, pid: str, gains: np.ndarray | float) -> np.ndarray:
    return (act.counts[pid] > 0).astype(np.float64)


def _spike_table(dec: Decoder, act: Activity, pid: str, gains: np.ndarray | float) -> np.ndarray:
    return dec.table_values(act.first_spike[pid], gains)


Decode = Callable[[Decoder, Activity, str, "np.ndarray | float"], np.ndarray]

#: Decoding functions by decoder ``kind``: ``(decoder, activity, population, gains) -> (frames,
#: size)``, ``gains`` per neuron (:meth:`~compiler.snn.Decoder.neuron_gains`) or 1.0.
DECODERS: dict[str, Decode] = {
    "spike_time": _spike_time,
    "count": _count,
    "membrane": _membrane,
    "spiked": _spiked,
    "spike_table": _spike_table,
}


@lru_cache(maxsize=8)
def _neuron_gains(dec: Decoder, shape: tuple[tuple[str, int], ...]) -> np.ndarray | float:
    """``dec.neuron_gains`` of a population's shape, kept for the next frames (read-only)."""
    gains = dec.neuron_gains(dict(shape))
    if isinstance(gains, np.ndarray):
        gains.flags.writeable = False
    return gains


def check_decoders(network: SpikingNetwork) -> None:
    """Refuse decoders the simulator cannot honour.

    Raises
    ------
    NetworkError
        A ``membrane`` decoder on a spike source (no membrane), a ``combine``
        whose population does not end with a ``part`` axis of the right size, or
        gains along an axis the population lacks, along ``part``, or of the wrong length.

    Examples
    --------
    >>> from compiler.snn import Decoder, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=2,
    ...     populations=[Population(id="a", shape={"i": 2})],
    ...     decoders=[Decoder(port="y", population="a", kind="count", combine="re_im")])
    >>> try:
    ...     check_decoders(net)
    ... except NetworkError as err:
    ...     print(err.node, "|", str(err)[:40])
    y | decoder 'y': combine 're_im' needs popul
    """
    pops = network.population
    for dec in network.decoders:
        pop = pops[dec.population]
        if dec.kind == "membrane" and pop.source:
            raise NetworkError(f"decoder {dec.port!r}: population {pop.id!r} is a spike source "
                               "and has no membrane; decode 'spike_time', 'count' or 'spiked'",
                               node=dec.port)
        parts = N_PARTS[dec.combine]
        if parts and (pop.axes[-1] != PART_AXIS or pop.dims[-1] != parts):
            raise NetworkError(f"decoder {dec.port!r}: combine {dec.combine!r} needs population "
                               f"{pop.id!r} to end with axis {PART_AXIS!r} of size {parts}, got "
                               f"{pop.shape}", node=dec.port)
        if dec.gain_axis == PART_AXIS:
            raise NetworkError(f"decoder {dec.port!r}: gains run along a value axis, not "
                               f"{PART_AXIS!r}", node=dec.port)
        _neuron_gains(dec, tuple(pop.shape.items()))  # (checked once, kept for decoding)


def decode_outputs(
    network: SpikingNetwork,
    activity: Activity,
    framed: bool,
    decoders: Mapping[str, Decode] = DECODERS,
) -> dict[str, np.ndarray]:
    """Decode every output port of ``network`` from ``activity``.

    Parameters
    ----------
    network : SpikingNetwork
        The simulated network.
    activity : Activity
        The engine's record.
    framed : bool
        Keep the leading frames axis (the inputs had one).
    decoders : mapping
        Decoding function per kind (default :data:`DECODERS`).

    Returns
    -------
    dict of str to ndarray
        Values per port: ``(n_frames, *value_shape)`` or ``value_shape``.

    Examples
    --------
    >>> from compiler.snn import Decoder, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=8,
    ...     populations=[Population(id="a", shape={"i": 2})],
    ...     decoders=[Decoder(port="t", population="a", kind="spike_time", t_ref=8.0,
    ...                       missing=-1.0)])
    >>> act = Activity(first_spike={"a": np.array([[3, -1]])}, counts={}, membrane={},
    ...                synaptic_events={})
    >>> decode_outputs(net, act, framed=False)["t"].tolist()
    [5.0, -1.0]

    With gains ``(1, 4)`` along ``i`` the second neuron's value is divided by 4:

    >>> net.decoders = [Decoder(port="t", population="a", kind="spike_time", t_ref=8.0,
    ...                         missing=-1.0, gain_axis="i", gains=(1.0, 4.0))]
    >>> act.first_spike["a"] = np.array([[3, 0]])
    >>> decode_outputs(net, act, framed=False)["t"].tolist()
    [5.0, 2.0]
    """
    pops = network.population
    out = {}
    for dec in network.decoders:
        pop = pops[dec.population]
        y = decoders[dec.kind](dec, activity, pop.id, _neuron_gains(dec, tuple(pop.shape.items())))
        y = combine_parts(y.reshape(-1, *pop.dims), dec.combine)
        out[dec.port] = y if framed else y[0]
    return out
