"""Run a saved radarsnn network in Lava's bit-accurate fixed-point processes (Python 3.10 side).

``python lava_worker.py ARTIFACT INPUTS.npz OUT.npz`` — started by :mod:`backends.lava` in the
cross-check environment (Lava 0.10, numpy 1.26).  It imports nothing of radarsnn: the
network comes from the artifact (:mod:`backends.crosscheck.chipnet`, loaded from its file),
the source spike rasters from ``INPUTS.npz`` (``src:<population>``, bool
``(frames, n_steps, n)``).  It builds ``RingBuffer`` sources, ``Dense``/``DelayDense``
synapse groups with their ``weight_exp`` and ``LIF`` neurons run with
``Loihi2SimCfg(select_tag="fixed_pt")`` (``PyLifModelBitAcc``, ``PyDenseModelBitAcc``),
writes the registers between run segments (:mod:`backends.crosscheck.frames`) and saves
``spikes:<population>`` and ``v:<population>`` (raw LSBs) on radarsnn's steps, ``scale:``
(raw LSBs per state unit) and ``notes``.  A network with no chip equivalent writes
``refused`` with the reason.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np


def _shared():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "crosscheck"))
    import chipnet
    import frames
    return chipnet, frames


def run(artifact: str, inputs_path: str, out_path: str) -> None:
    """Build, run and record (see the module doc)."""
    chipnet, frames = _shared()
    try:
        net = chipnet.chip_network(artifact)
    except chipnet.NotExpressible as err:
        np.savez(out_path, refused=np.array(str(err)))
        return
    from lava.magma.core.run_conditions import RunSteps
    from lava.magma.core.run_configs import Loihi2SimCfg
    from lava.proc.dense.process import DelayDense, Dense
    from lava.proc.io.source import RingBuffer
    from lava.proc.lif.process import LIF
    from lava.proc.monitor.process import Monitor
    from lava.utils.weightutils import SignMode

    with np.load(inputs_path, allow_pickle=False) as z:
        rasters = {k[4:]: z[k] for k in z.files if k.startswith("src:")}
    n_frames = next(iter(rasters.values())).shape[0]
    max_delay = max((int(p.delays.max(initial=0)) for p in net.projections), default=0)
    period = frames.frame_period(net.n_steps, net.max_lag, max_delay)
    total = n_frames * period
    procs = {pid: RingBuffer(data=frames.source_raster(rasters[pid], period))
             for pid in net.sources}
    lifs = {}
    for pid, pop in net.populations.items():
        lifs[pid] = LIF(shape=(pop.size,), du=pop.du, dv=pop.dv, vth=pop.vth,
                        bias_mant=np.zeros(pop.size, int), bias_exp=np.zeros(pop.size, int),
                        name=pid)
    procs.update(lifs)
    modes = {"mixed": SignMode.MIXED, "excitatory": SignMode.EXCITATORY,
             "inhibitory": SignMode.INHIBITORY}
    for proj in net.projections:
        kw = {"weights": proj.weights, "weight_exp": proj.weight_exp,
              "sign_mode": modes[proj.sign_mode], "num_weight_bits": 8}
        conn = (DelayDense(delays=proj.delays, **kw) if proj.delays.any() else Dense(**kw))
        procs[proj.source].s_out.connect(conn.s_in)
        conn.a_out.connect(lifs[proj.target].a_in)
    monitors = {}
    for pid, lif in lifs.items():
        ms, mv = Monitor(), Monitor()
        ms.probe(lif.s_out, total)
        mv.probe(lif.v, total)
        monitors[pid] = (ms, mv)
    writes = frames.host_writes(net, n_frames, period)
    cfg = Loihi2SimCfg(select_tag="fixed_pt")
    anchor = next(iter(lifs.values()))
    done = 0
    try:
        for step in sorted(set(writes) | {total}):
            if step > done:
                anchor.run(condition=RunSteps(num_steps=step - done), run_cfg=cfg)
                done = step
            for pid, regs in writes.get(step, []):
                _write(lifs[pid], net.populations[pid].size, regs)
        data = {pid: (ms.get_data()[pid]["s_out"], mv.get_data()[pid]["v"])
                for pid, (ms, mv) in monitors.items()}
    finally:
        anchor.stop()
    out = {"notes": np.array(net.notes or [""])}
    for pid, (s, v) in data.items():
        pop = net.populations[pid]
        s = np.asarray(s).reshape(total, -1) != 0
        v = np.asarray(v).reshape(total, -1).astype(np.int64)
        v = frames.aligned(v, n_frames, period, pop.lag, net.n_steps)
        s = frames.aligned(s, n_frames, period, pop.lag, net.n_steps)
        out[f"spikes:{pid}"] = frames.decided(v, pop) if pop.gated else s
        out[f"v:{pid}"] = v
        out[f"scale:{pid}"] = np.array(pop.scale)
    np.savez(out_path, **out)


def _write(lif, size: int, regs: dict) -> None:
    for name, value in regs.items():
        var = getattr(lif, name)
        var.set(np.full(size, value))


if __name__ == "__main__":
    run(*sys.argv[1:4])
