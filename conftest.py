"""Repository-wide pytest set-up (tests/conftest.py holds the fixtures).

Importing brian2 (the optional extra, imported by tests/test_brian2_*.py) replaces
pytest's ``DoctestModule`` with brian2's own subclass, which cannot collect the
doctests of a package ``__init__.py`` (``IndexError`` in brian2/tests/__init__.py).
Every collector restores pytest's class before it collects.
"""

from __future__ import annotations

import _pytest.doctest

_DOCTEST_MODULE = _pytest.doctest.DoctestModule


def pytest_collectstart(collector) -> None:
    _pytest.doctest.DoctestModule = _DOCTEST_MODULE
