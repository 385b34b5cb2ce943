"""Imports go one way through the layers (issue 20, item 4), checked by walking every module.

Bottom to top:

0. ``ir.errors`` — the error hierarchy; imports nothing first-party;
1. ``radar`` — the domain (FMCW configuration, scenes, conventional DSP); imports only
   the errors;
2. ``ir`` — the graph IR and its reference interpreter (built on the domain's DSP);
3. the compile path — ``compiler`` (passes, lowering, hardware, report …), nothing of
   ``backends``;
4. ``backends`` — the simulator, artifacts, exporters, emission;
5. the applications — ``compiler.cli``, ``compiler.demo``, ``compiler.bench``,
   ``compiler.sweep``, ``backends.emit.command``, ``backends.crosscheck.command``,
   ``radarsnn``: anything below.

A module may import its own layer and those below; function-level imports count too
(a lazy import is still a dependency).  :data:`EXCEPTIONS` lists each remaining upward
import with the reason it is there.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("ir", "radar", "compiler", "backends", "radarsnn")
APPLICATIONS = ("compiler.cli", "compiler.demo", "compiler.bench", "compiler.sweep",
                "backends.emit.command", "backends.crosscheck.command", "radarsnn")

#: (importer, imported) -> why the upward import stays (none today; the test below keeps
#: the mechanism honest: an entry that is no longer needed fails).
EXCEPTIONS: dict[tuple[str, str], str] = {}


def layer(module: str) -> int:
    """The layer of a first-party module (see the module docstring)."""
    if module == "ir.errors":
        return 0
    if any(module == a or module.startswith(a + ".") for a in APPLICATIONS):
        return 5
    top = module.split(".")[0]
    return {"radar": 1, "ir": 2, "compiler": 3, "backends": 4}[top]


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports() -> list[tuple[str, str, int]]:
    """``(importer, imported, line)`` of every first-party import outside ``TYPE_CHECKING``."""
    found = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)
                           and "TYPE_CHECKING" in ast.unparse(block.test)
                           for n in ast.walk(block)}
            for node in ast.walk(tree):
                if id(node) in typing_only:
                    continue
                if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                    names = [node.module]
                elif isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                else:
                    continue
                found += [(_module_name(path), n, node.lineno) for n in names
                          if n.split(".")[0] in PACKAGES]
    return found


def test_the_walk_sees_the_imports():
    edges = {(a, b) for a, b, _ in imports()}
    assert ("compiler.compile", "compiler.passes") in edges  # a plain top-level import
    assert ("ir.graph", "ir.serialize") in edges  # a function-level one
    assert len(edges) > 300


def test_every_exception_is_still_needed():
    edges = {(a, b) for a, b, _ in imports()}
    stale = [edge for edge in EXCEPTIONS if edge not in edges]
    assert not stale, f"{stale} are gone: drop them from EXCEPTIONS"


def upward(edges: list[tuple[str, str, int]]) -> list[str]:
    """The edges that climb the layers (less the listed exceptions), one line each."""
    return [f"{a} (line {line}) imports {b}: layer {layer(a)} -> {layer(b)}"
            for a, b, line in edges
            if layer(b) > layer(a) and (a, b.rsplit(".", 1)[0]) not in EXCEPTIONS
            and (a, b) not in EXCEPTIONS]


def test_imports_only_go_down_the_layers():
    found = upward(imports())
    assert not found, "\n".join(found)


@pytest.mark.parametrize(("importer", "imported"), [
    ("radar.cfar", "ir.graph"),                       # the domain reaching into the IR
    ("ir.interpreter", "compiler.compile"),           # the IR into the compiler
    ("compiler.passes.calibrate", "backends.reference"),  # the compile path into the simulator
    ("backends.reference.simulate", "compiler.cli"),  # a backend into an application
])
def test_a_back_edge_is_caught(importer, imported, tmp_path, monkeypatch):
    """The check fails on an upward import — shown on a module written for the purpose."""
    assert upward([(importer, imported, 1)])  # the rule itself
    package = tmp_path / importer.split(".")[0]  # and the walk that feeds it: a real file
    module = package.joinpath(*importer.split(".")[1:]).with_suffix(".py")
    module.parent.mkdir(parents=True)
    module.write_text(f"def f():\n    from {imported} import x  # a back-edge\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    found = upward(imports())
    assert len(found) == 1 and f"imports {imported}" in found[0], found


def test_the_errors_and_the_domain_import_no_ir():
    """``import ir.errors`` (what radar does) must not load the IR: radar is below it."""
    import subprocess

    code = ("import sys, radar, radar.cfar, radar.clustering, radar.tracking; "
            "print(sorted(m for m in sys.modules if m.startswith(('ir.', 'compiler', "
            "'backends'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.strip()
    assert out == "['ir.errors']", out


def test_function_level_imports_say_why():
    """Outside the applications, a first-party import inside a function carries its reason.

    The applications (CLI, demo, bench, sweep, emit command) import a command's machinery
    only when the command runs, so ``radarsnn --help`` starts fast; everywhere else a
    function-level import is there for a cycle that cannot be avoided by construction
    (``ir.graph``'s chain-file methods and ``ir.serialize``), an optional or heavy
    dependency (matplotlib), or a listed layer exception — and says so in a comment.
    """
    silent = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            module = _module_name(path)
            if layer(module) == 5:
                continue
            lines = path.read_text(encoding="utf-8").splitlines()
            tree = ast.parse("\n".join(lines))
            for fn in ast.walk(tree):
                if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                    continue
                for node in ast.walk(fn):
                    if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                        names = [node.module]
                    elif isinstance(node, ast.Import):
                        names = [a.name for a in node.names]
                    else:
                        continue
                    if not any(n.split(".")[0] in PACKAGES for n in names):
                        continue
                    here, above = lines[node.lineno - 1], lines[node.lineno - 2]
                    if "#" not in here and not above.strip().startswith("#"):
                        silent.append(f"{module}:{node.lineno}: {here.strip()}")
    assert not silent, "function-level imports without a reason:\n" + "\n".join(silent)
