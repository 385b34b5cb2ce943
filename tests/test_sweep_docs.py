"""The Python blocks of docs/sweeps.md run as written."""

from __future__ import annotations

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "sweeps.md"


def test_python_blocks_of_the_sweeps_page_run(monkeypatch, capsys):
    monkeypatch.chdir(DOC.parents[1])
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
    assert blocks
    for block in blocks:
        exec(compile(block, str(DOC), "exec"), {})  # noqa: S102 - our own documentation
    assert "{'chain': 'os', 'time_steps': 64}" in capsys.readouterr().out
