"""Shared test fixtures: the real captures in ``../shared/data`` and hypothesis profiles."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("dev", max_examples=100, deadline=None)
settings.register_profile(
    "deep", max_examples=5000, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

_ROOT = Path(__file__).resolve().parents[1]


def data_dir() -> Path:
    """Where the real captures live: ``$RADARSNN_DATA`` or ``<repo>/../shared/data``."""
    env = os.environ.get("RADARSNN_DATA")
    return Path(env) if env else _ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder of real captures; skips (with the reason) where it is absent."""
    path = data_dir()
    if not (path / "ti_chirps" / "data_tum.npy").is_file():
        if os.environ.get("CI"):
            pytest.fail(f"real captures not found at {path}; CI must have shared/ beside the clone")
        pytest.skip(f"real captures not found at {path}; set RADARSNN_DATA to shared/data")
    return path


@pytest.fixture
def disk_full(monkeypatch, tmp_path):
    """``with disk_full(free=n):`` — writes below ``tmp_path`` fail with ENOSPC after ``n`` bytes.

    See ``tests/faults.py`` (``os.write``, ``open`` and ``io.open`` are patched).
    """
    from faults import DiskFull

    return DiskFull(monkeypatch, tmp_path)
