"""Hand-made networks with the structure of the papers' stages, for sizing and tests.

They have the shapes, connectivity and ``origin`` of the lowerings' networks but
not their calibrated weights (weights are ±1 / the OS rank), so they size a
target exactly without running the lowerings.

Examples
--------
>>> net = os_cfar_network()
>>> net.n_neurons, net.n_synapse_instances()
(16384, 2899968)
"""

from __future__ import annotations

import numpy as np

from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
    StencilProjection,
)

__all__ = ["os_cfar_network", "dft_network", "imaging_network"]

_CODE = LatencyCode(t_max=100, x_min=0.0, x_max=1.0)


def os_cfar_kernel(guard: int = 3, train: int = 4, k: int = 132) -> np.ndarray:
    """A square OS-CFAR window: −1 on training cells, ``k`` on the CUT, 0 on guard cells.

    With whole weights and threshold 1 the membrane ``k − B`` is a whole number, so the
    neuron fires iff ``B ≤ k − 1`` exactly (no half margin needed) and an 8-bit target
    stores ``k`` as ``mantissa·2^e`` without rounding (132 = 33·2²).
    """
    w = 2 * (guard + train) + 1
    kern = -np.ones((w, w))
    kern[train:w - train, train:w - train] = 0.0
    kern[w // 2, w // 2] = float(k)
    return kern


def os_cfar_network(n_doppler: int = 64, n_range: int = 256, *, guard: int = 3, train: int = 4,
                    k: int = 132, n_steps: int = 100, node: str = "det") -> SpikingNetwork:
    """The spiking OS-CFAR of Table 3: one fire-once neuron per cell, a 15 × 15 stencil.

    176 training taps + 1 CUT tap over a ``[doppler, range]`` map (Doppler wrapped,
    range clipped): 16 384 neurons and 16 384 × 177 = 2 899 968 synapses at 64 × 256.
    """
    origin = {"node": node, "motif": "os_cfar"}
    shape = {"doppler": n_doppler, "range": n_range}
    return SpikingNetwork(
        name=f"{node}-os-cfar", n_steps=n_steps,
        populations=[Population(id=f"{node}_in", shape=shape, source=True, origin=origin),
                     Population(id=node, shape=shape, origin=origin,
                                params=NeuronParams(reset="fire_once"))],
        projections=[StencilProjection(id=f"{node}_window", source=f"{node}_in", target=node,
                                       axes=("doppler", "range"),
                                       kernel=os_cfar_kernel(guard, train, k),
                                       edge=("wrap", "clip"), origin=origin)],
        encoders=[Encoder(port=f"{node}_in", population=f"{node}_in", code=_CODE)],
        decoders=[Decoder(port=node, population=node, kind="spiked")]).validate()


def _dft(node: str, src: Population, axis: str, out_axis: str, n_out: int, parts_in: int,
         origin_motif: str = "dft") -> tuple[Population, MatrixProjection]:
    shape = {(out_axis if a == axis else a): (n_out if a == axis else n)
             for a, n in src.shape.items()}
    shape["part"] = 4
    origin = {"node": node, "motif": origin_motif}
    pop = Population(id=node, shape=shape, origin=origin)
    n_in = src.shape[axis] * parts_in
    proj = MatrixProjection(id=f"{node}_w", source=src.id, target=node, contract=(axis, "part"),
                            produce=(out_axis, "part"), weights=np.ones((n_in, n_out * 4)),
                            origin=origin)
    return pop, proj


def dft_network(reps: dict[str, int] | None = None, n_samples: int = 256, *,
                n_steps: int = 200) -> SpikingNetwork:
    """A dense two-ReLU DFT along ``sample``, shared over ``reps`` (default rx 4 × chirp 64).

    Inputs ``{*reps, sample, part: 2}`` (Re, Im), neurons ``{*reps, range, part: 4}``
    (±Re, ±Im), one dense ``2N × 4N`` matrix.
    """
    reps = {"rx": 4, "chirp": 64} if reps is None else reps
    src = Population(id="adc", shape={**reps, "sample": n_samples, "part": 2}, source=True,
                     origin={"node": "adc", "motif": "input"})
    pop, proj = _dft("rng", src, "sample", "range", n_samples, 2)
    return SpikingNetwork(name="dft", n_steps=n_steps, populations=[src, pop],
                          projections=[proj],
                          encoders=[Encoder(port="adc", population="adc", code=_CODE,
                                            split="re_im")]).validate()


def imaging_network(n_rx: int = 192, n_chirps: int = 256, n_samples: int = 512, *,
                    n_steps: int = 300) -> SpikingNetwork:
    """Range, Doppler and angle DFTs (dense two-ReLU) and an OS-CFAR over the RD map per angle.

    The 192-virtual-antenna imaging chain of the issue: 512 samples × 256 chirps × 192 rx.
    """
    src = Population(id="adc", shape={"rx": n_rx, "chirp": n_chirps, "sample": n_samples,
                                      "part": 2}, source=True,
                     origin={"node": "adc", "motif": "input"})
    rng, w1 = _dft("rng", src, "sample", "range", n_samples, 2)
    dop, w2 = _dft("dop", rng, "chirp", "doppler", n_chirps, 4)
    ang, w3 = _dft("ang", dop, "rx", "angle", n_rx, 4)
    cfar = os_cfar_network(n_chirps, n_samples, node="det")
    cin, cdet = cfar.populations
    cin = cin.model_copy(update={"shape": {"angle": n_rx, **cin.shape}})
    cdet = cdet.model_copy(update={"shape": {"angle": n_rx, **cdet.shape}})
    return SpikingNetwork(
        name="imaging", n_steps=n_steps, populations=[src, rng, dop, ang, cin, cdet],
        projections=[w1, w2, w3, *cfar.projections],
        encoders=[Encoder(port="adc", population="adc", code=_CODE, split="re_im"),
                  *cfar.encoders], decoders=cfar.decoders).validate()
