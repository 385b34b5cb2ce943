"""What replacing a directory may delete: the entries an earlier save wrote, and no others.

:func:`~backends.atomic.replace_directory` is told which entries of the old directory an
earlier save wrote (``owned``, relative paths at every depth); everything else is
*foreign*.  :func:`foreign_entries` lists those, :func:`check_replaceable` refuses a
replacement that would delete them (or the working directory), and
:func:`carry_foreign` keeps them instead, hard-linked (or copied) into the new tree.

Examples
--------
>>> import tempfile
>>> with tempfile.TemporaryDirectory() as tmp:
...     root = Path(tmp)
...     (root / "net").mkdir()
...     for name in ("net/a.npz", "net/notes.txt", "manifest.json"):
...         _ = (root / name).write_bytes(b"")
...     foreign_entries(root, {"net", "net/a.npz", "manifest.json"})
['net/notes.txt']
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from ir.errors import ArtifactError

__all__ = ["carry_foreign", "check_replaceable", "foreign_entries"]


def foreign_entries(root: Path, owned: set[str]) -> list[str]:
    """The relative paths below ``root`` that are not ``owned`` (an owned folder is entered).

    A symbolic link is an entry of its own (never followed); a foreign folder is one
    entry (what it holds is not listed).
    """
    foreign, todo = [], [""]
    while todo:
        rel = todo.pop()
        with os.scandir(root / rel) as it:
            for entry in it:
                name = f"{rel}/{entry.name}" if rel else entry.name
                if name not in owned:
                    foreign.append(name)
                elif entry.is_dir(follow_symlinks=False):
                    todo.append(name)
    return sorted(foreign)


def check_replaceable(target: Path, owned: set[str] | None, shown: object,
                  keep: bool) -> list[str]:
    """The foreign entries of ``target`` (``owned``: None if it does not exist); refuse
    what replacing it would destroy (``shown``: its name)."""
    try:
        cwd = Path.cwd().resolve()
    except OSError:  # the working directory was deleted
        cwd = None
    if cwd is not None and (target == cwd or target in cwd.parents):
        raise ArtifactError(f"cannot replace {shown}: it is (or holds) the current working "
                            "directory; save into a sub-directory or change directory first")
    if owned is None:
        return []
    foreign = foreign_entries(target, owned)
    if foreign and not keep:
        raise ArtifactError(
            f"cannot replace {shown}: it holds {len(foreign)} entries that an earlier save did "
            f"not write ({', '.join(map(repr, foreign[:5]))}); saving replaces only what it "
            "wrote, so save into an empty or new directory, or move them away first")
    return foreign


def _link_or_copy(src: str, dst: str) -> None:
    """A hard link of ``src`` at ``dst`` (the same file: nothing is copied), else a copy."""
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)


def carry_foreign(old: Path, new: Path, foreign: list[str], shown: object) -> None:
    """Put each ``foreign`` entry of the ``old`` tree at the same place in the ``new`` one."""
    for rel in foreign:
        src, dst = old / rel, new / rel
        if os.path.lexists(dst):
            raise ArtifactError(f"cannot replace {shown}: its entry {rel!r} was not written by an "
                                "earlier save and the new one writes that name; move it away "
                                "first")
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir() and not src.is_symlink():
            shutil.copytree(src, dst, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(str(src), str(dst))
