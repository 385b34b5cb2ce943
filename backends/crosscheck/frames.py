"""The time line both cross-check workers run: frames one after another, host writes between.

Shared by the workers (numpy only, no radarsnn import).  Every frame takes ``period`` chip
steps: the network's ``n_steps``, plus its deepest lag, plus its longest delay, plus 2
quiet steps, so that nothing of one frame reaches the next.  A population's frame ``f``
starts at chip step ``f·period + lag``; there the host writes ``u = v = 0`` and the first
phase's bias, at each later phase start that phase's bias (``u = 0`` when the phase cuts
the input), and at the frame's end a quiet state (bias 0, ``u = v = 0``).  The threshold
is never written: Lava's bit-accurate LIF computes ``vth << 6`` once per run
(``isthrscaled``), as the chip holds it in a per-core profile.

Examples
--------
>>> frame_period(n_steps=100, max_lag=1, max_delay=16)
119
"""

from __future__ import annotations

import numpy as np

__all__ = ["aligned", "decided", "frame_period", "host_writes", "source_raster"]


def frame_period(n_steps: int, max_lag: int, max_delay: int) -> int:
    """Chip steps one frame takes (see the module doc)."""
    return n_steps + max_lag + max_delay + 2


def host_writes(net, n_frames: int, period: int) -> dict[int, list[tuple[str, dict]]]:
    """``{chip step: [(population, registers to write before that step)]}``."""
    writes: dict[int, list[tuple[str, dict]]] = {}
    for pid, pop in net.populations.items():
        for f in range(n_frames):
            base = f * period + pop.lag
            for k, seg in enumerate(pop.segments):
                regs = {"bias_mant": seg["bias_mant"], "bias_exp": seg["bias_exp"]}
                if k == 0:
                    regs.update(u=0, v=0)
                elif not seg["input_on"]:
                    regs.update(u=0)
                writes.setdefault(base + seg["start"], []).append((pid, regs))
            quiet = {"bias_mant": 0, "bias_exp": 0, "u": 0, "v": 0}
            writes.setdefault(base + net.n_steps, []).append((pid, quiet))
    return writes


def source_raster(spikes: np.ndarray, period: int) -> np.ndarray:
    """``(n, n_frames·period)`` chip-time raster of a source's ``(frames, n_steps, n)`` spikes."""
    frames, n_steps, n = spikes.shape
    out = np.zeros((n, frames * period), np.int32)
    for f in range(frames):
        out[:, f * period:f * period + n_steps] = spikes[f].T
    return out


def aligned(raster: np.ndarray, n_frames: int, period: int, lag: int, n_steps: int) -> np.ndarray:
    """``(frames, n_steps, n)`` radarsnn-time view of a ``(chip steps, n)`` record."""
    return np.stack([raster[f * period + lag:f * period + lag + n_steps] for f in range(n_frames)])


def decided(v_raw: np.ndarray, pop) -> np.ndarray:
    """Spikes decided from the membrane, ``v ≥ S·θ`` on the steps whose phase may spike.

    For a population with a phase that may not spike, the chip runs with the largest
    ``vth`` and radarsnn's decision is read from its membrane (first crossing per neuron
    and frame, as radarsnn's fire-once neurons spike).
    """
    on = np.zeros(v_raw.shape[1], bool)
    for seg in pop.segments:
        on[seg["start"]:seg["stop"]] = seg["spiking_on"]
    hit = (v_raw >= pop.scale * pop.theta) & on[None, :, None]
    return hit & (np.cumsum(hit, axis=1) == 1)
