"""backends.reference.heap: glibc's thresholds held where its own rule ends, by the command only."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from backends.reference import heap

GLIBC = heap._glibc() is not None

#: A worker thread that makes and frees three 8 MiB arrays per frame, as a frame of the closed
#: form does: with glibc's defaults its heap gives them back and faults them in every frame.
FRAMES = textwrap.dedent("""
    import resource, sys, threading
    import numpy as np
    if sys.argv[1] == "hold":
        from backends.reference.heap import hold_freed_memory
        assert hold_freed_memory()
    def frames():
        for _ in range(30):
            a, b, c = np.ones(2**20), np.ones(2**20), np.ones(2**20)
            del a, b, c
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    worker = threading.Thread(target=frames)
    worker.start()
    worker.join()
    print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
""")


def _faults(mode: str) -> int:
    done = subprocess.run([sys.executable, "-c", FRAMES, mode], capture_output=True, text=True,
                          check=True)
    return int(done.stdout)


@pytest.mark.skipif(not GLIBC, reason="mallopt's thresholds are glibc's")
def test_a_held_heap_stops_faulting_in_a_worker_threads_frames() -> None:
    """Page faults are counted, not timed: the held heap faults its pages in once."""
    default, held = _faults("default"), _faults("hold")
    frame_pages = 3 * 2**23 // 4096  # one frame's arrays, in 4 KiB pages
    assert default > 5 * frame_pages  # frame after frame faults its arrays in again
    assert held < 2 * frame_pages, (default, held)


@pytest.mark.skipif(not GLIBC, reason="mallopt's thresholds are glibc's")
def test_hold_records_the_thresholds_it_set() -> None:
    assert heap.hold_freed_memory()
    assert heap.held() == (heap.MMAP_THRESHOLD_BYTES, heap.TRIM_THRESHOLD_BYTES)


def test_not_glibc_changes_nothing(monkeypatch) -> None:
    monkeypatch.setattr(heap, "_glibc", lambda: None)
    monkeypatch.setattr(heap, "_held", None)
    assert heap.hold_freed_memory() is False
    assert heap.held() is None


@pytest.mark.parametrize("argv, holds", [(["run", "no-such-dir", "-i", "x.npy"], True),
                                         (["schema"], False)])
def test_only_the_radarsnn_process_holds_its_heap(monkeypatch, capsys, argv, holds) -> None:
    """``main()`` as the console script (argv from sys.argv) holds for the commands that run
    frames; ``main(argv)`` called from a program never touches the program's malloc."""
    from radarsnn import cli

    calls = []
    monkeypatch.setattr(heap, "hold_freed_memory", lambda: calls.append(1) or True)
    monkeypatch.setattr(sys, "argv", ["radarsnn", *argv])
    cli.main()
    assert calls == ([1] if holds else [])
    calls.clear()
    cli.main(argv)
    assert calls == []
    capsys.readouterr()


def test_the_commands_that_run_frames_hold() -> None:
    from radarsnn.cli import build_parser

    parser = build_parser()
    for argv in (["demo"], ["bench"], ["run", "p", "-i", "x.npy"], ["sweep", "s.yaml"]):
        assert parser.parse_args(argv).holds_freed_memory, argv
    assert not getattr(parser.parse_args(["schema"]), "holds_freed_memory", False)


@pytest.mark.parametrize("bad", [0, -1, 2**31, 1.5, "32M", None, True])
def test_a_threshold_that_malloc_cannot_take_is_refused(bad) -> None:
    from ir.errors import SimulationError

    with pytest.raises(SimulationError, match="whole number of bytes"):
        heap.hold_freed_memory(mmap_threshold_bytes=bad)
    with pytest.raises(SimulationError, match="trim_threshold_bytes"):
        heap.hold_freed_memory(trim_threshold_bytes=bad)
