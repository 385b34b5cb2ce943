"""Every ```python block of docs/*.md runs: the documentation's examples are tests.

A page's blocks run in order in one namespace (a later block may use an earlier
block's names), with the repository root as the working directory.  A block is
skipped when the line just before its opening fence is the HTML comment ``<!-- no-test -->``
(kept for blocks that need optional extras, real hardware or long runs; the
comment carries the reason after the marker, e.g. ``<!-- no-test: needs brian2 -->``).
Examples that write files write them under ``tempfile.mkdtemp()``, never into the
repository.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from doc_blocks import fenced_blocks  # one fence scanner for the docs tests

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def python_blocks(text: str) -> list[tuple[int, str, bool]]:
    """``(first line number, code, skipped)`` of every ```python block of a Markdown text.

    Examples
    --------
    >>> md = "x\\n<!-- no-test: slow -->\\n```python\\na = 1\\n```\\n```python\\nb = 2\\n```\\n"
    >>> python_blocks(md)
    [(4, 'a = 1\\n', True), (7, 'b = 2\\n', False)]
    """
    return [(b.line + 1, b.code, b.no_test is not None)
            for b in fenced_blocks(text) if b.lang == "python"]


def test_python_blocks_parser_finds_fences_and_markers() -> None:
    md = ("# t\n```bash\nls\n```\n<!-- no-test -->\n```python\nraise SystemExit\n```\n"
          "text\n```python\nx = 1\ny = x + 1\n```\n```\nplain\n```\n")
    assert python_blocks(md) == [(7, "raise SystemExit\n", True), (11, "x = 1\ny = x + 1\n", False)]


PAGES = sorted(p for p in DOCS.glob("*.md") if any(not s for *_, s in python_blocks(p.read_text())))


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_docs_page_runs(page: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    namespace: dict[str, object] = {"__name__": f"docs_{page.stem}"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # examples may warn (e.g. clipped inputs); they must run
        for line, code, skipped in python_blocks(page.read_text()):
            if skipped:
                continue
            try:
                exec(compile(code, f"{page.name}:{line}", "exec", dont_inherit=True), namespace)
            except Exception as exc:  # re-raised with the block's location
                raise AssertionError(f"{page.name}, block at line {line} failed: "
                                     f"{type(exc).__name__}: {exc}") from exc


def test_every_page_is_linked_from_the_index() -> None:
    index = (DOCS / "index.md").read_text()
    missing = [p.name for p in DOCS.glob("*.md")
               if p.name != "index.md" and f"({p.name})" not in index]
    assert not missing, f"docs/index.md does not link {missing}"


def test_no_test_markers_are_rare() -> None:
    skipped = {p.name: sum(s for *_, s in python_blocks(p.read_text())) for p in DOCS.glob("*.md")}
    total = sum(len(python_blocks(p.read_text())) for p in DOCS.glob("*.md"))
    assert sum(skipped.values()) <= total // 2, f"too many no-test blocks: {skipped}"

