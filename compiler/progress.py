"""Progress of long work on the terminal: a :mod:`tqdm` bar fed by ``progress(stage, message)``.

The compiler's passes and the demo report progress through a plain callback
``progress(stage, message)`` (see :data:`compiler.passes.base.Progress`);
:class:`ProgressBar` turns those calls into a bar on ``stderr`` (so ``--json``
output on ``stdout`` stays clean), and :func:`make_progress` returns a silent
callback for ``--quiet``.

Examples
--------
>>> import io
>>> stream = io.StringIO()
>>> with ProgressBar(total=2, desc="compile", file=stream) as bar:
...     bar("verify", "start"); bar("verify", "done"); bar("lower", "done")
>>> "compile" in stream.getvalue()
True
>>> make_progress(quiet=True)("lower", "done") is None
True
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import IO

from tqdm import tqdm

__all__ = ["ProgressBar", "bar_without_thread", "make_progress"]


class bar_without_thread(tqdm):  # noqa: N801 - used as tqdm is, a callable bar
    """A :class:`tqdm.tqdm` bar that starts no monitor thread.

    tqdm's monitor thread only shortens the refresh of a stalled bar; without it the
    process keeps running no other thread, which is what lets a frames axis fork its
    worker processes safely (:func:`backends.reference.frames_run.resolve_parallel`).
    """

    monitor_interval = 0


class ProgressBar:
    """A callable ``progress(stage, message)`` that advances a bar on every ``"done"``.

    Parameters
    ----------
    total : int, optional
        Stages expected (None: an open-ended counter).
    desc : str
        The bar's label.
    file : file-like, optional
        Where to draw (default ``sys.stderr``).
    """

    def __init__(self, total: int | None = None, desc: str = "", file: IO[str] | None = None):
        self._label = desc
        self._bar = bar_without_thread(
            total=total, desc=desc, file=file or sys.stderr, leave=False,
            disable=None if file is None else False,  # None: no bar off a terminal
            dynamic_ncols=True, bar_format="[{elapsed}] {n_fmt}/{total_fmt} {desc}")

    def __call__(self, stage: str, message: str) -> None:
        self._bar.set_description_str(f"{self._label}: {stage} {message}", refresh=False)
        if message == "done":
            self._bar.update(1)
        else:
            self._bar.refresh()

    def close(self) -> None:
        """Remove the bar from the terminal."""
        self._bar.close()

    def __enter__(self) -> ProgressBar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _silent(_stage: str, _message: str) -> None:
    return None


def make_progress(quiet: bool, total: int | None = None,
                  desc: str = "") -> Callable[[str, str], None]:
    """A :class:`ProgressBar` on stderr, or a silent callback when ``quiet``."""
    return _silent if quiet else ProgressBar(total=total, desc=desc)
