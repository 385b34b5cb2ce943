"""Lava 0.10's bit-accurate fixed-point processes as a cross-check of the reference engine.

:func:`run_lava` runs a network in ``lava_worker.py`` (a subprocess of the Python 3.10
cross-check environment, :mod:`backends.crosscheck.env`) and returns its rasters and
membranes beside the reference step engine's int64 run; :func:`backends.crosscheck.run.compare`
sets them side by side.  The worker reads only the saved artifact.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from backends.crosscheck.run import ChipRun, run_chip_model
from backends.reference import SimResult
from compiler.snn import SpikingNetwork

__all__ = ["run_lava"]


def run_lava(network: SpikingNetwork, inputs: Mapping[str, np.ndarray],
             python: Path | None = None) -> tuple[ChipRun, SimResult]:
    """``network`` in Lava's ``Loihi2SimCfg(select_tag="fixed_pt")`` and in the reference."""
    return run_chip_model("lava", network, inputs, python=python)
