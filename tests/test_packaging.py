"""The wheel holds the import packages (the four libraries and the application ``radarsnn``),
marked as typed, the real captures of ``radar/data``, and nothing the user's runs leave
beside them."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_package_patterns_match_the_import_packages_only(tmp_path) -> None:
    setuptools = pytest.importorskip("setuptools")
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    find = config["tool"]["setuptools"]["packages"]["find"]
    for name in ("ir", "compiler/passes", "backends", "radar", "radarsnn/cli"):
        (tmp_path / name).mkdir(parents=True)
        (tmp_path / name / "__init__.py").write_text("")
    for stray in ("radarsnn-demo", "radar_runs", "irdata", "build"):  # what runs leave here
        (tmp_path / stray).mkdir()
        (tmp_path / stray / "a.png").write_text("x")
    found = setuptools.find_namespace_packages(where=tmp_path, include=find["include"])
    assert sorted(found) == ["backends", "compiler", "compiler.passes", "ir", "radar", "radarsnn",
                             "radarsnn.cli"]


def test_the_public_package_is_typed_and_packed() -> None:
    tomllib = pytest.importorskip("tomllib")
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "py.typed" in config["tool"]["setuptools"]["package-data"]["radarsnn"]
    assert (ROOT / "radarsnn" / "py.typed").is_file()


def test_every_shipped_capture_is_package_data():
    """A regular (non-editable) install copies ``radar/data``: pyproject's globs cover it all."""
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    globs = config["tool"]["setuptools"]["package-data"]["radar"]
    package = ROOT / "radar"
    shipped = {p.relative_to(package).as_posix() for p in (package / "data").rglob("*")
               if p.is_file() and "__pycache__" not in p.parts}
    covered = {p.relative_to(package).as_posix() for g in globs for p in package.glob(g)}
    assert {"data/README.md", "data/ti_chirps/LICENSE", "data/openradar/LICENSE",
            "data/ti_chirps/data_tum.npy", "data/openradar/simple_frame_1.npy"} <= shipped
    assert shipped == covered


def test_the_public_names_resolve() -> None:
    import radarsnn

    missing = [n for n in radarsnn.__all__ if not hasattr(radarsnn, n)]
    assert not missing
    assert isinstance(radarsnn.__version__, str) and radarsnn.__version__[0].isdigit()
    assert issubclass(radarsnn.BudgetError, radarsnn.CompileError)
    assert issubclass(radarsnn.CompileError, radarsnn.RadarSNNError)


def test_the_public_names_load_on_first_use() -> None:
    """``import radarsnn`` (and so the command line, :mod:`radarsnn.cli`) loads no numpy;
    ``__all__`` is every name of :data:`radarsnn.HOMES` and of the chain module, once."""
    import subprocess
    import sys

    code = ("import sys, radarsnn\nprint(sorted(m for m in ('numpy', 'compiler', 'backends') "
            "if m in sys.modules))\nfrom radarsnn import *\nprint(type(Graph).__name__)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True)
    assert done.stdout.splitlines() == ["[]", "type"]
    import radarsnn
    from radarsnn import HOMES, _chain

    names = [n for home in HOMES.values() for n in home]
    assert set(radarsnn.__all__) == {"__version__", *radarsnn._errors.__all__, *names,
                                     *_chain.__all__}
    assert len(radarsnn.__all__) == len(set(radarsnn.__all__))
    assert set(radarsnn.__all__) <= set(dir(radarsnn))
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        radarsnn.not_a_name  # noqa: B018


def test_the_console_script_is_the_application_package() -> None:
    """The console script ``radarsnn`` is :func:`radarsnn.cli.main`, as ``python -m radarsnn``."""
    from importlib import import_module

    tomllib = pytest.importorskip("tomllib")
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    module, _, name = config["project"]["scripts"]["radarsnn"].partition(":")
    assert module.split(".")[0] == "radarsnn"
    assert getattr(import_module(module), name) is import_module("radarsnn.__main__").main
