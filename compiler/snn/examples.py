"""The small example network the documentation's examples run: two inputs, one neuron.

:func:`tiny_network` builds it, so an example about saving, exporting or running a
network starts from one line instead of a copy of its construction (which
:mod:`compiler.snn.network` shows in full).

Examples
--------
>>> net = tiny_network()
>>> [p.id for p in net.populations], net.n_synapses, net.decoders[0].kind
(['in', 'out'], 2, 'spiked')
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from compiler.snn.codes import LatencyCode, RateCode
from compiler.snn.coding import Decoder, Encoder
from compiler.snn.network import Population, SpikingNetwork
from compiler.snn.neurons import NeuronParams
from compiler.snn.projections import MatrixProjection

__all__ = ["tiny_network"]


def tiny_network(*, n_steps: int = 8, params: NeuronParams | None = None,
                 code: LatencyCode | RateCode | None = None,
                 kind: Literal["spiked", "spike_time", "count"] = "spiked",
                 delays: np.ndarray | None = None, scoped: bool = False) -> SpikingNetwork:
    """Two spike sources summed through unit weights into one neuron.

    Input port ``x`` feeds the source population ``in`` (axis ``i`` of 2) through
    ``code``; the projection ``w`` (contract ``i``, produce ``o``, weights ``[[1], [1]]``)
    drives the population ``out`` (axis ``o`` of 1), read at output port ``y``.

    Parameters
    ----------
    n_steps : int
        Steps of one frame.
    params : NeuronParams, optional
        The neuron; default an IF neuron of threshold 2 (``NeuronParams(v_th=2.0)``).
    code : LatencyCode or RateCode, optional
        The input code; default a latency code over the whole frame, ``x`` in ``[0, 1]``.
    kind : {"spiked", "spike_time", "count"}
        The decoder; ``spike_time`` reads the first spike's step (``scale=-1``).
    delays : ndarray, optional
        ``(2, 1)`` synaptic delays of the projection (default none).
    scoped : bool
        Name the parts as the compiler names a node's (``x/in``, ``y/out``, ``y/w``).

    Returns
    -------
    SpikingNetwork
        The network, validated.

    Examples
    --------
    >>> net = tiny_network(n_steps=6, params=NeuronParams(du=0.0, v_th=3.0,
    ...                    reset="fire_once"), kind="spike_time", scoped=True)
    >>> [p.id for p in net.populations], net.projections[0].id, net.decoders[0].scale
    (['x/in', 'y/out'], 'y/w', -1.0)
    """
    src, dst, proj = ("x/in", "y/out", "y/w") if scoped else ("in", "out", "w")
    code = code if code is not None else LatencyCode(t_max=n_steps, x_min=0.0, x_max=1.0)
    scale = -1.0 if kind == "spike_time" else 1.0
    return SpikingNetwork(
        name="tiny", n_steps=n_steps,
        populations=[Population(id=src, shape={"i": 2}, source=True),
                     Population(id=dst, shape={"o": 1},
                                params=params if params is not None else NeuronParams(v_th=2.0))],
        projections=[MatrixProjection(id=proj, source=src, target=dst, contract=("i",),
                                      produce=("o",), weights=np.ones((2, 1)), delays=delays)],
        encoders=[Encoder(port="x", population=src, code=code)],
        decoders=[Decoder(port="y", population=dst, kind=kind, scale=scale)],
    ).validate()
