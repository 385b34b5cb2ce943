"""Run a saved network in a chip model (worker subprocess) and compare it with the reference.

:func:`run_chip_model` saves the network (``backends.save``), encodes the inputs with the
reference encoders into source spike rasters, starts the model's worker in the
cross-check environment (:mod:`backends.crosscheck.env`) and reads back its rasters and
membranes.  :func:`compare` sets them beside the reference step engine's int64 run: every
spike of every population on the same step — for fire-once populations the first spike of
each neuron, since the chip's stock neuron fires again after its reset to 0.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from backends.artifact import save
from backends.crosscheck.env import CrosscheckEnvError, env_python
from backends.reference import SimResult, simulate
from compiler.snn import Decoder, SpikingNetwork
from ir.errors import SimulationError

__all__ = ["WORKERS", "ChipRun", "PopulationMatch", "compare", "membrane_difference",
           "reference_run",
           "run_chip_model", "run_saved"]

#: The worker script of each model, beside this package.
WORKERS: dict[str, Path] = {
    "lava": Path(__file__).resolve().parents[1] / "lava" / "lava_worker.py",
    "nengo-loihi": Path(__file__).resolve().parents[1] / "nengo_loihi" / "emulator_worker.py",
}
#: Longest one worker run may take, s.
WORKER_TIMEOUT_S = 900.0


@dataclass
class ChipRun:
    """What a chip model produced: per population ``(frames, n_steps, n)`` spikes and raw
    membranes, the raw LSBs per state unit, the worker's notes, or why it refused."""

    model: str
    spikes: dict[str, np.ndarray] = field(default_factory=dict)
    v_raw: dict[str, np.ndarray] = field(default_factory=dict)
    scale: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    refused: str | None = None


@dataclass
class PopulationMatch:
    """One population's comparison: spikes (or first spikes) compared and mismatches."""

    population: str
    compared: str
    n_spikes_ref: int
    n_spikes_chip: int
    mismatched: int

    @property
    def exact(self) -> bool:
        """Whether every compared spike is on the same step."""
        return self.mismatched == 0


def reference_run(network: SpikingNetwork, inputs: Mapping[str, np.ndarray]) -> SimResult:
    """The reference step engine in int64 with every raster recorded, and each neuron
    population's membrane after the last step as output ``v:<population>``."""
    extra = [Decoder(port=f"v:{p.id}", population=p.id, kind="membrane")
             for p in network.populations if not p.source]
    probed = replace(network, decoders=[*network.decoders, *extra])
    return simulate(probed, inputs, mode="step", arithmetic="int64", record_spikes=True,
                    out_of_range="clip")


def membrane_difference(network: SpikingNetwork, reference: SimResult,
                        chip: ChipRun) -> dict[str, float]:
    """Per neuron population, ``max |v_chip / S − v_ref|`` after the last step, state units."""
    out = {}
    for pop in network.populations:
        if pop.source or pop.id not in chip.v_raw:
            continue
        ref = reference.outputs[f"v:{pop.id}"].reshape(reference.n_frames, -1)
        got = chip.v_raw[pop.id][:, -1, :] / chip.scale[pop.id]
        out[pop.id] = float(np.abs(got - ref).max(initial=0.0))
    return out


def run_saved(model: str, artifact: Path, rasters: Mapping[str, np.ndarray],
              python: Path | None = None, workdir: Path | None = None) -> ChipRun:
    """Run the worker of ``model`` on a saved network and source rasters.

    Raises
    ------
    CrosscheckEnvError
        No cross-check environment (``radarsnn crosscheck --build-env`` builds it).
    SimulationError
        The worker failed (its last lines of output).
    """
    if model not in WORKERS:
        raise SimulationError(f"unknown chip model {model!r}; choose one of {', '.join(WORKERS)}")
    python = python or env_python()
    if python is None:
        raise CrosscheckEnvError("no cross-check environment: run `radarsnn crosscheck "
                                 "ARTIFACT --with lava --build-env` once (needs Python 3.10)")
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        inp, out = Path(tmp) / "inputs.npz", Path(tmp) / "out.npz"
        np.savez(inp, **{f"src:{pid}": np.asarray(r, bool) for pid, r in rasters.items()})
        done = subprocess.run([str(python), str(WORKERS[model]), str(artifact), str(inp),
                               str(out)], capture_output=True, text=True,
                              timeout=WORKER_TIMEOUT_S, check=False, cwd=tmp)
        if done.returncode != 0 or not out.is_file():
            tail = " | ".join((done.stderr or done.stdout).strip().splitlines()[-4:])
            raise SimulationError(f"the {model} worker failed (exit {done.returncode}): {tail}")
        with np.load(out, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    run = ChipRun(model)
    if "refused" in data:
        run.refused = str(data["refused"])
        return run
    run.notes = [n for n in data["notes"].tolist() if n]
    for key, value in data.items():
        kind, _, pid = key.partition(":")
        if kind == "spikes":
            run.spikes[pid] = value.astype(bool)
        elif kind == "v":
            run.v_raw[pid] = value.astype(np.int64)
        elif kind == "scale":
            run.scale[pid] = int(value)
    return run


def run_chip_model(model: str, network: SpikingNetwork, inputs: Mapping[str, np.ndarray],
                   reference: SimResult | None = None,
                   python: Path | None = None) -> tuple[ChipRun, SimResult]:
    """Save ``network``, run it in ``model`` on the reference encoders' rasters of ``inputs``.

    Returns the chip run and the reference run (int64 step engine) it was fed from.
    """
    reference = reference or reference_run(network, inputs)
    rasters = {p.id: _flat(reference.spikes[p.id]) for p in network.populations if p.source}
    with tempfile.TemporaryDirectory() as tmp:
        folder = save(network, Path(tmp) / "net")
        return run_saved(model, folder, rasters, python), reference


def compare(network: SpikingNetwork, reference: SimResult, chip: ChipRun) -> list[PopulationMatch]:
    """Every non-source population, spike for spike (first spikes for fire-once ones)."""
    out = []
    for pop in network.populations:
        if pop.source or pop.id not in chip.spikes:
            continue
        ref, got = _flat(reference.spikes[pop.id]), chip.spikes[pop.id]
        if pop.params.reset == "fire_once":
            ref, got = _first(ref), _first(got)
            how = "first spikes"
        else:
            how = "all spikes"
        out.append(PopulationMatch(pop.id, how, int(ref.sum()), int(got.sum()),
                                   int((ref != got).sum())))
    return out


def _first(raster: np.ndarray) -> np.ndarray:
    """Only each neuron's first spike of each frame."""
    seen = np.cumsum(raster, axis=1)
    return raster & (seen == 1)


def _flat(raster: np.ndarray) -> np.ndarray:
    """``(frames, n_steps, n)``: the neurons in memory order."""
    return raster.reshape(raster.shape[0], raster.shape[1], -1)
