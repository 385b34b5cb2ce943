"""Run a saved radarsnn network in NengoLoihi 1.1's Loihi emulator (Python 3.10 side).

``python emulator_worker.py ARTIFACT INPUTS.npz OUT.npz`` — started by
:mod:`backends.nengo_loihi` in the cross-check environment. It imports nothing of radarsnn:
the network comes from the artifact (:mod:`backends.crosscheck.chipnet`, loaded from its
file), the source spike rasters from ``INPUTS.npz``. Each population is a ``LoihiBlock``
whose compartments hold the integer registers (``decay_u``, ``decay_v``, ``vth = vth_man <<
6``, ``bias``, ``vmin``/``vmax = ∓(2^23 − 1)``); each synapse group a ``Synapse`` whose
weights go through NengoLoihi's own ``discretize_weights`` with its ``SynapseConfig``
(weight exponent, mixed or one-sign fan-out); sources are ``SpikeInput`` s. The
``EmulatorInterface`` steps it (int32 arithmetic: ``decay_int(u, decay_u, offset=1)``, ``v >
vth``, reset to 0) with the host writes of :mod:`backends.crosscheck.frames` between steps.
The emulator has no synaptic delays (``CompartmentState.MAX_DELAY = 1``): a source's delays
become one ``SpikeInput`` per delay value, a delay between neurons is
refused.  Output as :mod:`backends.lava.lava_worker`.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np


def _shared():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "crosscheck"))
    import chipnet
    import frames
    return chipnet, frames


class _Model:
    """The little a ``nengo_loihi.emulator.EmulatorInterface`` reads of a model."""

    def __init__(self) -> None:
        self.blocks, self.inputs, self.probes, self.dt = [], [], [], 0.001


def run(artifact: str, inputs_path: str, out_path: str) -> None:
    """Build, step and record (see the module doc)."""
    chipnet, frames = _shared()
    try:
        net = chipnet.chip_network(artifact)
        for proj in net.projections:
            if proj.source not in net.sources and proj.delays.any():
                raise chipnet.NotExpressible(
                    f"projection {proj.id!r}: NengoLoihi's emulator models no synaptic "
                    "delays (CompartmentState.MAX_DELAY = 1)")
    except chipnet.NotExpressible as err:
        np.savez(out_path, refused=np.array(str(err)))
        return
    from nengo_loihi.block import Axon, LoihiBlock, Synapse
    from nengo_loihi.builder.discretize import discretize_weights
    from nengo_loihi.emulator.interface import EmulatorInterface
    from nengo_loihi.inputs import SpikeInput

    with np.load(inputs_path, allow_pickle=False) as z:
        rasters = {k[4:]: z[k] for k in z.files if k.startswith("src:")}
    n_frames = next(iter(rasters.values())).shape[0]
    max_delay = max((int(p.delays.max(initial=0)) for p in net.projections), default=0)
    period = frames.frame_period(net.n_steps, net.max_lag, max_delay)
    total = n_frames * period
    model, blocks = _Model(), {}
    vlim = (1 << 23) - 1
    for pid, pop in net.populations.items():
        block = LoihiBlock(pop.size, label=pid)
        c = block.compartment
        c.decay_u = np.full(pop.size, pop.du, np.int32)
        c.decay_v = np.full(pop.size, pop.dv, np.int32)
        c.scale_u = c.scale_v = False
        c.vth = np.full(pop.size, pop.vth << chipnet.ACT_SHIFT, np.int32)
        c.bias = np.zeros(pop.size, np.int32)
        c.vmin, c.vmax = -vlim, vlim
        c.refract_delay = np.zeros(pop.size, np.int32)
        blocks[pid] = block
        model.blocks.append(block)
    for proj in net.projections:
        _connect(proj, net, blocks, rasters, period, model, Axon, Synapse, SpikeInput,
                 discretize_weights)
    writes = frames.host_writes(net, n_frames, period)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = EmulatorInterface(model, seed=0)
    comp, slices = emu.compartment, emu.block_info.slices
    record = {pid: (np.zeros((total, p.size), bool), np.zeros((total, p.size), np.int64))
              for pid, p in net.populations.items()}
    for k in range(total):
        for pid, regs in writes.get(k, []):
            sl = slices[blocks[pid]]
            comp.bias[sl] = regs["bias_mant"] << regs["bias_exp"]
            if "u" in regs:
                comp.current[sl] = regs["u"]
            if "v" in regs:
                comp.voltage[sl] = regs["v"]
        emu.step()
        for pid, (s, v) in record.items():
            sl = slices[blocks[pid]]
            s[k], v[k] = comp.spiked[sl], comp.voltage[sl]
    out = {"notes": np.array(net.notes or [""])}
    for pid, (s, v) in record.items():
        pop = net.populations[pid]
        v = frames.aligned(v, n_frames, period, pop.lag, net.n_steps)
        s = frames.aligned(s, n_frames, period, pop.lag, net.n_steps)
        out[f"spikes:{pid}"] = frames.decided(v, pop) if pop.gated else s
        out[f"v:{pid}"] = v
        out[f"scale:{pid}"] = np.array(pop.scale)
    np.savez(out_path, **out)


def _connect(proj, net, blocks, rasters, period, model, Axon, Synapse, SpikeInput,
             discretize_weights) -> None:
    """One synapse group: per delay value (sources only) one Synapse and its axons."""
    target = blocks[proj.target]
    for delay in np.unique(proj.delays[proj.weights != 0]) if proj.weights.any() else []:
        w = np.where(proj.delays == delay, proj.weights, 0).T  # (n_pre, n_post)
        syn = Synapse(w.shape[0], label=f"{proj.id}@{delay}")
        syn.set_weights(w.astype(np.float32))
        syn.format(weight_exp=proj.weight_exp,
                   fanout_type=1 if proj.sign_mode == "mixed" else 2)
        syn.weights = [discretize_weights(syn.synapse_cfg, row.copy()) for row in syn.weights]
        target.add_synapse(syn)
        axon = Axon(w.shape[0], label=syn.label)
        axon.target = syn
        if proj.source in blocks:
            blocks[proj.source].add_axon(axon)
            continue
        src = SpikeInput(w.shape[0], label=syn.label)
        src.add_axon(axon)
        raster = rasters[proj.source]
        for f in range(raster.shape[0]):
            for t in range(raster.shape[1]):
                idx = np.flatnonzero(raster[f, t])
                if idx.size:
                    src.add_spikes(f * period + t + int(delay) + 1, idx.tolist())
        model.inputs.append(src)


if __name__ == "__main__":
    run(*sys.argv[1:4])
