"""Every documented command session of README.md and docs/*.md runs, as the python blocks do.

A *session block* is a fenced ```bash, ```sh, ```shell or ```console block with a
``radarsnn`` command in it (in a ```console block only the ``$ `` lines run).  The
blocks of one page run in order, as bash scripts (``set -e -o pipefail``), in one
temporary folder holding a copy of ``examples/`` — a session may span blocks: files
and the working directory (a ``cd``) carry over — with a ``radarsnn`` that runs
``python -m radarsnn`` of this source tree (whatever the installed script points at),
then the ``bin`` folder of this interpreter's virtual environment (its ``python``), first
on ``PATH``, this tree first on ``PYTHONPATH`` and ``RADARSNN_DATA`` pointing at the real
captures.  Each must exit 0.

Markers on the line just before the opening fence:

* ``<!-- no-test: REASON -->`` — the block is not run (a pip install, a long
  benchmark, a remote scheduler); the test is reported as skipped with REASON;
* ``<!-- requires: MODULE[, MODULE] -->`` — the block needs an optional extra; it
  is skipped (naming the module) where one is not importable.

A block that reads the real captures (``radar.loaders``) skips without them,
except under CI, where they must be there (``tests/conftest.py``).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from doc_blocks import SHELLS, Block, fenced_blocks  # the fence scanner test_docs.py shares

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BIN = Path(sys.executable).parent  # the virtual environment's bin (python, pip)
TIMEOUT_S = 600

#: Run around every block: stop at the first failing command and name it; keep the cwd.
WRAPPER = """set -eo pipefail
trap 'echo "documented command failed (exit status $?): $BASH_COMMAND" >&2' ERR
cd "$1"
{code}
pwd > "$2"
"""


def sessions(page: Path) -> list[Block]:
    """The session blocks of a page, in order."""
    return [b for b in fenced_blocks(page.read_text(encoding="utf-8"), page.name) if b.is_session]


BLOCKS = [b for page in PAGES for b in sessions(page)]


@dataclass
class Workspace:
    """One page's temporary folder, its working directory and the blocks run in it."""

    cwd: Path
    state: Path
    bin: Path  # holds the ``radarsnn`` the blocks call
    ran: dict[int, str | None] = field(default_factory=dict)  # line -> None ok, or the failure


@pytest.fixture(scope="module")
def workspaces(tmp_path_factory: pytest.TempPathFactory):
    made: dict[str, Workspace] = {}
    command = tmp_path_factory.mktemp("bin") / "radarsnn"  # this tree's command line
    command.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m radarsnn "$@"\n')
    command.chmod(0o755)

    def get(page: str) -> Workspace:
        if page not in made:
            base = tmp_path_factory.mktemp(Path(page).stem)
            shutil.copytree(ROOT / "examples", base / "work" / "examples")
            made[page] = Workspace(cwd=base / "work", state=base / "cwd", bin=command.parent)
        return made[page]

    return get


def _environment(bin_dir: Path) -> dict[str, str]:
    from radar.loaders import default_data_dir  # $RADARSNN_DATA or the shipped radar/data

    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(bin_dir), str(BIN), env.get("PATH", "")])
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    env["RADARSNN_DATA"] = str(default_data_dir().resolve())
    env["MPLBACKEND"] = "Agg"
    return env


def _why_not(block: Block, request: pytest.FixtureRequest) -> str | None:
    """Why the block cannot run here (None: it can); may skip through ``shared_data``."""
    if block.no_test is not None:
        return block.no_test
    missing = [m for m in block.requires if importlib.util.find_spec(m) is None]
    if missing:
        return f"needs the optional {', '.join(missing)} package (an extra of pyproject.toml)"
    if "radar.loaders" in block.code:
        request.getfixturevalue("shared_data")  # skips without the captures (fails under CI)
    return None


def _run(block: Block, space: Workspace) -> str | None:
    """Run one block in the page's workspace; None, or what failed."""
    cwd = Path(space.state.read_text().strip()) if space.state.is_file() else space.cwd
    try:
        done = subprocess.run(
            ["bash", "-c", WRAPPER.format(code=block.script()), block.where, str(cwd),
             str(space.state)], env=_environment(space.bin), capture_output=True, text=True,
            timeout=TIMEOUT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return f"{block.where}: still running after {TIMEOUT_S} s"
    if done.returncode == 0:
        return None
    return (f"{block.where}: exit status {done.returncode}\n--- stderr (end) ---\n"
            f"{done.stderr[-3000:]}\n--- stdout (end) ---\n{done.stdout[-1500:]}")


@pytest.mark.parametrize("block", BLOCKS, ids=[b.where for b in BLOCKS])
def test_documented_session_runs(block: Block, workspaces, request: pytest.FixtureRequest
                                 ) -> None:
    reason = _why_not(block, request)
    if reason is not None:
        pytest.skip(f"{block.where}: {reason}")
    space = workspaces(block.page)
    for earlier in BLOCKS:  # a session spans blocks: run the page's earlier ones first
        if earlier.page != block.page or earlier.line >= block.line:
            continue
        if earlier.line not in space.ran and _why_not(earlier, request) is None:
            space.ran[earlier.line] = _run(earlier, space)
        if space.ran.get(earlier.line) is not None:
            pytest.fail(f"an earlier block of the session failed: {space.ran[earlier.line]}")
    if block.line not in space.ran:
        space.ran[block.line] = _run(block, space)
    assert space.ran[block.line] is None, space.ran[block.line]


def test_the_parser_reads_markers_and_console_prompts() -> None:
    md = ("text\n<!-- requires: nir, h5py -->\n```sh\nradarsnn export-nir a -o b.nir\n```\n"
          "```\nradarsnn validate x.yaml\n```\n```console\n$ radarsnn compile c.yaml \\\n"
          "    -o out\ncompiled\n$ ls out\n```\n```bash\npip install radarsnn[nir]\n```\n")
    blocks = fenced_blocks(md)
    assert [(b.lang, b.requires, b.is_session) for b in blocks] == [
        ("sh", ("nir", "h5py"), True), ("", (), False), ("console", (), True),
        ("bash", (), False)]
    assert blocks[2].script() == "radarsnn compile c.yaml \\\n    -o out\nls out\n"


def test_every_command_block_is_a_tagged_shell_block() -> None:
    """A command block left untagged (or tagged text) would silently escape the tests."""
    untagged = [b.where for page in PAGES
                for b in fenced_blocks(page.read_text(encoding="utf-8"), page.name)
                if b.lang not in (*SHELLS, "python")
                and re.search(r"^\s*(?:\$\s+)?radarsnn\s", b.code, re.M)]
    assert not untagged, f"tag these command blocks ```bash (or ```console): {untagged}"


def test_no_test_markers_name_their_reason() -> None:
    marked = [b for b in BLOCKS if b.no_test is not None]
    assert all(b.no_test for b in marked), [b.where for b in marked if not b.no_test]
    assert len(marked) <= len(BLOCKS) // 2, [b.where for b in marked]
    assert {"cli.md", "getting-started.md", "howto-chain.md"} <= {
        b.page for b in BLOCKS if b.no_test is None}


def test_pages_with_command_sessions_say_to_activate_the_venv() -> None:
    """``radarsnn`` is on ``PATH`` only in the activated venv: each page says so before its
    first session that calls it by that name (``.venv/bin/radarsnn`` needs no activation)."""
    silent = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        bare = [b for b in sessions(page) if re.search(r"(?<![/\w])radarsnn\s", b.code)]
        if not bare:
            continue
        before = "\n".join(text.splitlines()[: bare[0].line])
        if "source .venv/bin/activate" not in before:
            silent.append(bare[0].where)
    assert not silent, f"say `source .venv/bin/activate` before these sessions: {silent}"


#: What a user of a clone cannot reach: paths outside the repository, the developers' notes,
#: their issues (any mention), session numbers and lead, papers named by a file number.
UNREACHABLE = re.compile(r"\.\./shared|/work/|/tmp/|NOTES(?:\.md| §)|\b[Ii]ssue(?:s|'s)?\b|"
                         r"\b[Ss]essions? \d|\b[Pp]apers? 00\d|\b00\d paper|\bthe lead\b")


def test_no_page_names_what_a_user_cannot_reach() -> None:
    found = [f"{page.name}:{n}: {m.group(0)}" for page in PAGES
             for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
             for m in [UNREACHABLE.search(line)] if m]
    assert not found, found
