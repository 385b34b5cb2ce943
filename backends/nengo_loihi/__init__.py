"""NengoLoihi 1.1's Loihi emulator as a cross-check of the reference engine.

:func:`run_nengo_loihi` runs a network in ``emulator_worker.py`` (a subprocess of the
Python 3.10 cross-check environment, :mod:`backends.crosscheck.env`) and returns its
rasters and membranes beside the reference step engine's int64 run.  The worker reads only
the saved artifact.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from backends.crosscheck.run import ChipRun, run_chip_model
from backends.reference import SimResult
from compiler.snn import SpikingNetwork

__all__ = ["run_nengo_loihi"]


def run_nengo_loihi(network: SpikingNetwork, inputs: Mapping[str, np.ndarray],
                    python: Path | None = None) -> tuple[ChipRun, SimResult]:
    """``network`` in NengoLoihi's ``EmulatorInterface`` (int32) and in the reference."""
    return run_chip_model("nengo-loihi", network, inputs, python=python)
