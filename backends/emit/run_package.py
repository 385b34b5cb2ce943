"""Run a generated package in a fresh Python interpreter (``python -m <package>``).

Useful to check that generated code is standalone: the child process sees only
the package directory on ``sys.path`` and the inputs as ``.npy`` files.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ir.errors import SimulationError

__all__ = ["run_package"]


def run_package(package: str | Path, inputs: Mapping[str, np.ndarray], *,
                out_of_range: str = "reject", timeout_s: float = 600.0
                ) -> tuple[dict[str, np.ndarray], list[dict[str, int]]]:
    """Run ``python -m <package> PORT=X.npy ... -o OUT.npz --counts`` in a subprocess.

    Parameters
    ----------
    package : str or Path
        The generated package directory (what :func:`~backends.emit.emit_numpy` returned).
    inputs : mapping of str to ndarray
        One array per input id / port.
    out_of_range : {"reject", "clip"}
        Input values above an encoder's range: refused (the package exits with one
        ``error:`` line naming the port, the count, the first index and the range,
        quoted in the ``SimulationError``), or clipped (``--clip``).
    timeout_s : float
        Give up after this many seconds.

    Returns
    -------
    outputs : dict of str to ndarray
    counts : list of dict
        Spikes per population of every spiking segment.

    Raises
    ------
    SimulationError
        If the child process fails (its stderr is quoted) or times out, or
        ``out_of_range`` is not ``reject`` or ``clip``.
    """
    if out_of_range not in ("reject", "clip"):
        raise SimulationError(f"run_package: out_of_range={out_of_range!r} is not 'reject' or "
                              "'clip' (the package's command line has --clip only)")
    folder = Path(package).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        args = []
        for j, (port, value) in enumerate(inputs.items()):
            path = Path(tmp) / f"in_{j}.npy"
            np.save(path, np.asarray(value), allow_pickle=False)
            args.append(f"{port}={path}")
        out = Path(tmp) / "out.npz"
        cmd = [sys.executable, "-m", folder.name, *args, "-o", str(out), "--counts",
               *(["--clip"] if out_of_range == "clip" else [])]
        try:
            done = subprocess.run(cmd, cwd=folder.parent, capture_output=True, text=True,
                                  timeout=timeout_s, check=False,
                                  env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
        except subprocess.TimeoutExpired as exc:
            raise SimulationError(f"{folder}: the generated simulator ran over {timeout_s} s"
                                  ) from exc
        if done.returncode != 0:
            raise SimulationError(f"{folder}: the generated simulator failed "
                                  f"(exit {done.returncode}):\n{done.stderr[-2000:]}")
        with np.load(out, allow_pickle=False) as npz:
            outputs = {key: npz[key] for key in npz.files}
        return outputs, json.loads(done.stdout)
