"""Fenced blocks of Markdown pages and their markers, for the tests that run the docs.

``tests/test_docs.py`` runs the ```python blocks, ``tests/test_docs_cli.py`` the shell
sessions; both read pages with :func:`fenced_blocks`.  A block is marked by the HTML
comment on the line just before its fence: ``<!-- no-test: reason -->`` (skipped) or
``<!-- requires: module, … -->`` (skipped where a module is not importable).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["COMMAND", "SHELLS", "Block", "fenced_blocks"]

SHELLS = ("bash", "sh", "shell", "console")
FENCE = re.compile(r"^```(\S*)\s*$")
MARKER = re.compile(r"^<!--\s*(no-test|requires)\b:?\s*(.*?)\s*-->$")
COMMAND = re.compile(r"(?:^|[\s/;&|(])radarsnn(?:\s|$)", re.M)


@dataclass(frozen=True)
class Block:
    """One fenced block of a page: where, its language, its code and its marker."""

    page: str
    line: int  # of the opening fence
    lang: str
    code: str
    no_test: str | None = None  # the reason, when marked no-test
    requires: tuple[str, ...] = ()

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"

    @property
    def is_session(self) -> bool:
        return self.lang in SHELLS and COMMAND.search(self.script()) is not None

    def script(self) -> str:
        """The commands: the code, or of a console block its ``$ `` lines (and continuations)."""
        if self.lang != "console":
            return self.code
        out, more = [], False
        for line in self.code.splitlines():
            if more or line.startswith("$ "):
                out.append(line[2:] if not more else line)
                more = line.rstrip().endswith("\\")
        return "\n".join(out) + "\n"


def fenced_blocks(text: str, page: str = "page.md") -> list[Block]:
    """Every fenced block of a Markdown text, with the marker of the line before it.

    Examples
    --------
    >>> md = ("<!-- no-test: slow -->\\n```bash\\nradarsnn bench\\n```\\n"
    ...       "```console\\n$ radarsnn validate x.yaml\\nx.yaml: ok\\n```\\n")
    >>> [(b.line, b.lang, b.no_test, b.is_session) for b in fenced_blocks(md)]
    [(2, 'bash', 'slow', True), (5, 'console', None, True)]
    >>> fenced_blocks(md)[1].script()
    'radarsnn validate x.yaml\\n'
    """
    lines, blocks, i = text.splitlines(), [], 0
    while i < len(lines):
        match = FENCE.match(lines[i].strip())
        if match is None:
            i += 1
            continue
        j = i + 1
        while j < len(lines) and lines[j].strip() != "```":
            j += 1
        marker = MARKER.match(lines[i - 1].strip()) if i > 0 else None
        kind, arg = (marker.group(1), marker.group(2)) if marker else (None, "")
        blocks.append(Block(page=page, line=i + 1, lang=match.group(1),
                            code="\n".join(lines[i + 1:j]) + "\n",
                            no_test=arg if kind == "no-test" else None,
                            requires=tuple(m.strip() for m in arg.split(",") if m.strip())
                            if kind == "requires" else ()))
        i = j + 1
    return blocks
