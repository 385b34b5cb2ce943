"""The cross-check environment: one Python 3.10 with Lava 0.10, NengoLoihi 1.1 and numpy 1.26.

Neither public model of Loihi's arithmetic installs beside radarsnn (numpy ≥ 2 for
Brian2; Lava needs Python < 3.11 and numpy < 2, NengoLoihi's emulator numpy < 2), so the
workers run in their own virtual environment, built on request in a cache folder
(``RADARSNN_CROSSCHECK_ENV``, default ``~/.cache/radarsnn/crosscheck-py310``) from a
Python 3.10 interpreter found on ``PATH`` or under pyenv.

Examples
--------
>>> PACKAGES[:2]
('numpy==1.26.4', 'networkx==2.8.7')
>>> default_env_dir().name
'crosscheck-py310'
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from ir.errors import RadarSNNError

__all__ = ["PACKAGES", "CrosscheckEnvError", "build_env", "default_env_dir", "env_python",
           "find_python310"]

#: What the environment holds (pinned: the versions the cross-check was written against).
PACKAGES: tuple[str, ...] = ("numpy==1.26.4", "networkx==2.8.7", "lava-nc==0.10.0",
                             "nengo==4.1.0", "nengo-loihi==1.1.0")
#: Longest a build may take, s (a fresh build from the package index takes ≈ 20–60 s).
BUILD_TIMEOUT_S = 600.0
_PROBE = ("import lava.proc.lif.models, nengo_loihi.emulator.interface, numpy; "
          "print(numpy.__version__)")


class CrosscheckEnvError(RadarSNNError):
    """The cross-check environment is missing or could not be built (the message says why)."""


def default_env_dir() -> Path:
    """``$RADARSNN_CROSSCHECK_ENV`` or ``~/.cache/radarsnn/crosscheck-py310``."""
    given = os.environ.get("RADARSNN_CROSSCHECK_ENV")
    return Path(given) if given else Path.home() / ".cache" / "radarsnn" / "crosscheck-py310"


def find_python310() -> Path | None:
    """A working Python 3.10: the newest pyenv 3.10.x, else ``python3.10`` on ``PATH``
    (each is run once; a pyenv shim with no 3.10 behind it does not count)."""
    root = Path(os.environ.get("PYENV_ROOT", Path.home() / ".pyenv")) / "versions"
    candidates = sorted(root.glob("3.10.*/bin/python"), key=lambda p: p.parent.parent.name)
    on_path = shutil.which("python3.10")
    for python in [*reversed(candidates), *([Path(on_path)] if on_path else [])]:
        try:
            probe = subprocess.run([str(python), "-c", "import sys, venv; print(sys.version_info"
                                    "[:2])"], capture_output=True, text=True, timeout=60,
                                   check=False)
        except OSError:
            continue
        if probe.returncode == 0 and probe.stdout.strip() == "(3, 10)":
            return python
    return None


def env_python(env_dir: Path | None = None) -> Path | None:
    """The environment's interpreter if it exists and imports Lava and NengoLoihi, else None."""
    python = (env_dir or default_env_dir()) / "bin" / "python"
    if not python.is_file():
        return None
    probe = subprocess.run([str(python), "-c", _PROBE], capture_output=True, text=True,
                           timeout=120, check=False)
    return python if probe.returncode == 0 else None


def build_env(env_dir: Path | None = None, timeout_s: float = BUILD_TIMEOUT_S) -> Path:
    """Create (or reuse) the environment and return its interpreter.

    Raises
    ------
    CrosscheckEnvError
        No Python 3.10 found, or ``venv``/``pip`` failed or ran past ``timeout_s``.
    """
    env_dir = env_dir or default_env_dir()
    ready = env_python(env_dir)
    if ready is not None:
        return ready
    base = find_python310()
    if base is None:
        raise CrosscheckEnvError("no Python 3.10 interpreter found (python3.10 on PATH or "
                                 "~/.pyenv/versions/3.10.*); Lava 0.10 needs Python < 3.11: "
                                 "install one (e.g. pyenv install 3.10) to cross-check")
    env_dir.parent.mkdir(parents=True, exist_ok=True)
    steps = ([str(base), "-m", "venv", "--clear", str(env_dir)],
             [str(env_dir / "bin" / "python"), "-m", "pip", "install", "-q",
              "--disable-pip-version-check", *PACKAGES])
    for cmd in steps:
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s,
                                  check=False)
        except subprocess.TimeoutExpired as err:
            raise CrosscheckEnvError(f"building the cross-check environment in {env_dir} "
                                     f"took more than {timeout_s:g} s at {cmd[2]!r}") from err
        if done.returncode != 0:
            tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
            raise CrosscheckEnvError(f"building the cross-check environment in {env_dir} "
                                     f"failed at {' '.join(cmd[:4])}: {' | '.join(tail)}")
    python = env_python(env_dir)
    if python is None:
        raise CrosscheckEnvError(f"the environment in {env_dir} was built but does not import "
                                 "Lava and NengoLoihi")
    return python
