"""The calibration notes of ``radarsnn compile``/``report``: what a compile without ``-c`` means.

Without calibration inputs a chain is calibrated on seeded synthetic noise
(:func:`compiler.calibration.synthetic_inputs`).  The stages, their motifs and the
steps per frame do not depend on it, but the calibrated value ranges set more
than the thresholds: the OS-CFAR's log code turns the threshold factor into a
delay of ``s·ln α`` steps (``s`` from the calibrated range, see
:mod:`compiler.lowering.cfar_codes`), and a delay beyond the target's maximum is
relayed through ``delay_relay`` populations (:mod:`compiler.passes.relay`): more
neurons, possibly more cores.  Weights are quantized at the calibrated scale, so
the weights that round to zero (not stored) change the synapse counts slightly.

Examples
--------
>>> SYNTHETIC_NOTE.startswith("calibrated on synthetic noise")
True
>>> artifact_note("no/such/folder")
'from the compiled artifact (its calibration is not recorded)'
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["GIVEN_NOTE", "SYNTHETIC_NOTE", "artifact_note"]

#: The note of a compile on ``-c`` inputs.
GIVEN_NOTE = "calibrated on the given inputs"

#: The note of a compile on synthetic noise: what it changes (one line, printed and stored).
SYNTHETIC_NOTE = (
    "calibrated on synthetic noise, not on radar data: its thresholds say nothing about "
    "accuracy, and the resources that follow from the calibrated ranges differ from a "
    "calibrated compile (OS-CFAR log-code delays beyond the target's maximum add delay_relay "
    "populations, hence neurons and cores; which weights round to zero changes the synapses); "
    "pass -c [NODE=]X.npy for figures that hold on your data")


def artifact_note(folder: str | Path) -> str:
    """The note of a compiled program folder: ``from the compiled artifact``, and its calibration.

    Parameters
    ----------
    folder : str or Path
        A ``radarsnn compile`` output (its ``program.json`` holds the compile's note
        under ``extra.calibration``).

    Returns
    -------
    str
        One line; says so when the folder does not record how it was calibrated.
    """
    try:
        extra = json.loads((Path(folder) / "program.json").read_text(encoding="utf-8"))["extra"]
        stored = extra.get("calibration") if isinstance(extra, dict) else None
    except (OSError, ValueError, KeyError, TypeError):
        stored = None
    if not isinstance(stored, str):
        return "from the compiled artifact (its calibration is not recorded)"
    return f"from the compiled artifact, {stored}"
