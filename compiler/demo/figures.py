"""The demo's figures (matplotlib, Agg): RD maps with detections, spike times, core map.

Each function writes one PNG and returns its path.  ``rd_maps`` draws the
conventional and the spiking range-Doppler map in dB side by side, detections
as dots and ground-truth bins as circles; ``spike_times`` draws the first
spike step of each neuron of a few populations (for the fire-once neurons of
the time-coded motifs this *is* the raster: each spikes at most once).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["rd_maps", "spike_times"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def rd_maps(path: Path, title: str, arrays) -> Path:
    """Conventional vs spiking RD maps (dB) with detections (dots) and truth (circles)."""
    plt = _pyplot()
    panels = [("conventional", arrays.conventional_db, arrays.conventional_mask)]
    if arrays.spiking_db is not None:
        panels.append(("spiking", arrays.spiking_db, arrays.spiking_mask))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), squeeze=False)
    vmax = float(arrays.conventional_db.max())
    for ax, (label, db, mask) in zip(axes[0], panels, strict=True):
        image = ax.imshow(db, origin="lower", aspect="auto", cmap="viridis",
                          vmin=vmax - 80.0, vmax=vmax, interpolation="nearest")
        r, d = np.nonzero(mask)
        ax.plot(d, r, ".", color="red", markersize=2, label=f"detections ({r.size} cells)")
        if arrays.truth_bins:
            tr, td = np.array(arrays.truth_bins).T
            ax.plot(td, tr, "o", markerfacecolor="none", markeredgecolor="white",
                    markersize=10, label="ground truth")
        ax.set_title(f"{title}: {label}")
        ax.set_xlabel("Doppler bin")
        ax.set_ylabel("range bin")
        ax.legend(loc="upper right", fontsize=7)
        fig.colorbar(image, ax=ax, label="power (dB)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def spike_times(path: Path, title: str, first_spikes: dict[str, np.ndarray],
                max_neurons: int = 512) -> Path:
    """First spike steps of a few populations (frame 0), ``max_neurons`` neurons each.

    Of each population the block of ``max_neurons`` consecutive neurons (flat
    index) with the most spikes is drawn, so a sparse stage still shows activity.
    """
    plt = _pyplot()
    n = max(1, len(first_spikes))
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.9 * n + 0.6), squeeze=False)
    for ax, (pid, steps) in zip(axes[:, 0], first_spikes.items(), strict=False):
        n_blocks = -(-steps.size // max_neurons)
        padded = np.full(n_blocks * max_neurons, -1, dtype=np.int64)
        padded[:steps.size] = steps
        block = int(np.argmax((padded.reshape(n_blocks, max_neurons) >= 0).sum(axis=1)))
        s = padded[block * max_neurons:(block + 1) * max_neurons]
        fired = np.flatnonzero(s >= 0)
        ax.plot(s[fired], fired + block * max_neurons, "|", markersize=3, color="black")
        ax.set_ylabel("neuron")
        ax.set_title(f"{pid}: neurons {block * max_neurons}–{(block + 1) * max_neurons - 1}, "
                     f"{fired.size} spiked ({int((steps >= 0).sum())} of {steps.size} in all)",
                     fontsize=9)
    axes[-1, 0].set_xlabel("time step")
    fig.suptitle(f"{title}: spike times (first spike per neuron, frame 0)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
