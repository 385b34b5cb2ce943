"""Run a snippet in a child interpreter under an address-space cap and a timeout.

A reader that reserves or decompresses gigabytes fails there with ``MemoryError`` (or is
killed by the timeout) instead of exhausting the test machine.  The cap is set *after*
``setup`` ran (imports, files), at the child's address space then plus ``headroom_bytes``,
so it bounds what ``body`` allocates, whatever numpy and scipy reserve at import.

Examples
--------
>>> done = run_capped("import numpy as np", "print(np.zeros(3).sum())", headroom_bytes=1 << 28)
>>> done.returncode, done.stdout.split()[0]
(0, '0.0')
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

_ROOT = Path(__file__).resolve().parents[1]

_CAP = """
import resource as _resource
_pages = int(open("/proc/self/statm").read().split()[0])
_now = _pages * _resource.getpagesize()
_hard = _resource.getrlimit(_resource.RLIMIT_AS)[1]
_resource.setrlimit(_resource.RLIMIT_AS, ({cap} + _now, _hard))
"""


def run_capped(setup: str, body: str, *, headroom_bytes: int = 1 << 30, timeout_s: float = 30.0,
               cwd: str | Path | None = None) -> subprocess.CompletedProcess:
    """``setup``, then ``body`` under ``RLIMIT_AS`` = the address space after setup + headroom.

    The child runs with this worktree first on ``PYTHONPATH`` and one BLAS thread; a
    timeout raises :class:`subprocess.TimeoutExpired` (the child is killed).
    """
    code = (textwrap.dedent(setup) + "\n" + _CAP.format(cap=int(headroom_bytes)) + "\n"
            + textwrap.dedent(body))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(_ROOT), os.environ.get(
        "PYTHONPATH", "")]), "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout_s, env=env, cwd=cwd or _ROOT)
