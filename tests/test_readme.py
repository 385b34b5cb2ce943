"""The README's quick start runs as written (it is the first thing a user copies)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quick_start_runs(capsys, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "README.md has no python quick start"
    monkeypatch.chdir(ROOT)
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})  # noqa: S102 - the README's own code
    out = capsys.readouterr().out
    assert "truth (range bin, Doppler bin)" in out


def test_readme_names_the_two_setup_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "radarsnn demo" in text
    assert "pytest" in text


def test_quick_start_needs_only_import_radarsnn():
    """The public package is enough: ops, presets, scenes, chains, compile, run."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    imports = {line.strip() for block in blocks for line in block.splitlines()
               if re.match(r"\s*(import|from)\s", line)}
    assert imports == {"import radarsnn"}, imports
