"""Shared test fixtures: the real captures shipped in ``radar/data`` and hypothesis profiles."""

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

def data_dir() -> Path:
    """Where the real captures live: ``$RADARSNN_DATA`` or the shipped ``radar/data``."""
    from radar.loaders import default_data_dir

    return default_data_dir()


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder of real captures; fails (with the reason) where it is absent.

    The captures ship with the package, so only a ``$RADARSNN_DATA`` naming a folder without
    them gets here.
    """
    path = data_dir()
    if not (path / "ti_chirps" / "data_tum.npy").is_file():
        pytest.fail(f"real captures not found at {path}; unset RADARSNN_DATA to read the "
                    f"copy shipped in radar/data, or point it at a folder holding ti_chirps/")
    return path


@pytest.fixture
def disk_full(monkeypatch, tmp_path):
    """``with disk_full(free=n):`` — writes below ``tmp_path`` fail with ENOSPC after ``n`` bytes.

    See ``tests/faults.py`` (``os.write``, ``open`` and ``io.open`` are patched).
    """
    from faults import DiskFull

    return DiskFull(monkeypatch, tmp_path)
