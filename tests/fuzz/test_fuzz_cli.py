"""Fuzz: ``radarsnn`` argument vectors — wrong paths, unreadable and damaged files, alias and
nesting bombs (chains, profiles, ``--option`` values), ``.npy`` headers declaring huge sizes,
bad options and values, hostile strings.  Every run exits 0 (or 1 for a failed check), or 2 with
exactly one line ``error: …`` on stderr (a JSON object on stdout with ``--json``) and never
a traceback.
"""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
import traceback
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import HOSTILE_STRINGS, budget, laughs, npy_header
from hypothesis import given, note
from hypothesis import strategies as st

from backends import save
from compiler.compile import compile_graph
from ir import Graph
from radarsnn.cli import main

TINY = """name: tiny
nodes:
  - {id: a, op: input, shape: {range: 8}, domain: power}
  - {id: c, op: cfar, input: a, kind: ca, guard: 0, train: 1, alpha: 1.5}
  - {id: o, op: output, input: c}
"""


@pytest.fixture(scope="module")
def files():
    with tempfile.TemporaryDirectory(prefix="fuzz-cli-") as tmp:
        root = Path(tmp)
        (root / "tiny.yaml").write_text(TINY)
        (root / "broken.yaml").write_text(TINY.replace("input: a,", "input: [a,"))
        (root / "cycle.yaml").write_text(TINY.replace("input: a,", "input: c,"))
        (root / "binary.yaml").write_bytes(bytes(range(256)))
        (root / "empty.yaml").write_text("")
        x = np.linspace(0.1, 1.0, 8)
        np.save(root / "x.npy", x)
        np.save(root / "x_big.npy", x * 100)
        np.save(root / "x_nan.npy", np.full(8, np.nan))
        np.save(root / "x_wrong.npy", np.zeros((2, 3)))
        (root / "x_bad.npy").write_bytes(b"\x93NUMPY junk")
        (root / "x_huge.npy").write_bytes(npy_header((10**12,), "<f8") + bytes(64))
        with (root / "x_sparse.npy").open("wb") as f:  # 4 GiB + 8 declared, held as holes
            head = npy_header(((1 << 29) + 1,), "<f8")
            f.write(head)
            f.truncate(len(head) + (4 << 30) + 8)
        (root / "laughs.yaml").write_text(f"name: {laughs(9, 9)}\nnodes: []\n")
        (root / "deep.yaml").write_text("name: x\nnodes: " + "[" * 5000 + "]" * 5000 + "\n")
        program = compile_graph(Graph.from_yaml(TINY), target="loihi2",
                                calibration_inputs={"a": x})
        save(program, root / "program")
        save(program.networks[0], root / "network")
        (root / "out").mkdir()
        yield root


def _pools(root: Path) -> dict[str, list[str]]:
    paths = [str(root / n) for n in ("tiny.yaml", "broken.yaml", "cycle.yaml", "binary.yaml",
                                     "empty.yaml", "missing.yaml", "program", "network", "out",
                                     "laughs.yaml", "deep.yaml")]
    paths += ["/dev/null", "/", "", "-", "\x01"]
    npys = [str(root / n) for n in ("x.npy", "x_big.npy", "x_nan.npy", "x_wrong.npy",
                                    "x_bad.npy", "nope.npy", "x_huge.npy", "x_sparse.npy")] + [
        str(root / "program")]
    inputs = npys + [f"{port}={p}" for port in ("a", "c/in", "bogus", "") for p in npys[:3]]
    return {
        "paths": paths,
        "inputs": inputs,
        "targets": ["loihi", "loihi2", "spinnaker2", "unbounded", "tpu", str(root / "tiny.yaml"),
                    str(root / "missing.yaml"), str(root / "binary.yaml"), "",
                    str(root / "laughs.yaml"), str(root / "deep.yaml")],
        "options": ["headroom=1.5", "headroom=-1", "headroom=nan", "bogus=1", "=1", "noeq",
                    "max_memory_bytes=10", "max_memory_bytes=-5", "max_time_s=0",
                    "cfar_ties=[1, 2]", "time_steps=3", "headroom={a: [}",
                    f"fft_radices={laughs(9, 9)}", "headroom=" + "[" * 5000, "headroom=&a [*a]",
                    "max_time_s=.nan", "max_memory_bytes=x"],
        "motifs": ["c=host", "c=bogus", "cfar=host", "ghost=host", "noeq", "c=", "=host"],
        "numbers": ["-1", "0", "1", "3", "64", "1e9", "abc", "99999999999999999999", ""],
        "out": [str(root / "out" / "art"), str(root / "out" / "r.npz"), str(root / "tiny.yaml"),
                "/proc/forbidden/x", str(root / "out" / "\u202e")],
    }


@st.composite
def argvs(draw: st.DrawFn, root: Path) -> list[str]:
    """One command line of ``radarsnn``."""
    p = _pools(root)
    pick = lambda key: draw(st.sampled_from(p[key]))  # noqa: E731
    junk = st.sampled_from(HOSTILE_STRINGS)
    command = draw(st.sampled_from(["validate", "schema", "compile", "report", "run", "emit",
                                    "bogus", "--version", "--help"]))
    argv = [command]
    if command == "validate":
        argv += [pick("paths") for _ in range(draw(st.integers(0, 2)))]
    elif command == "schema" and draw(st.booleans()):
        argv += ["-o", pick("out")]
    elif command in ("compile", "report", "emit"):
        argv += [pick("paths") if draw(st.integers(0, 3)) else str(root / "tiny.yaml")]
        if command in ("compile", "emit") or draw(st.booleans()):
            argv += ["-o", pick("out")]
        if draw(st.booleans()):
            argv += ["--target", pick("targets")]
        for flag, key in (("--option", "options"), ("--motif", "motifs"),
                          ("--time-steps", "numbers"), ("--calibration", "inputs")):
            if command == "emit" and flag in ("--option", "--motif"):
                continue
            if draw(st.integers(0, 3)) == 0:
                argv += [flag, pick(key)]
    elif command == "run":
        argv += [pick("paths") if draw(st.integers(0, 2)) == 0 else str(root / draw(
            st.sampled_from(["program", "network"])))]
        for _ in range(draw(st.integers(0, 2))):
            argv += ["-i", pick("inputs")]
        if draw(st.booleans()):
            argv += ["--mode", draw(st.sampled_from(["step", "closed", "auto", "fast"]))]
        if draw(st.booleans()):
            argv += ["--clip"]
        if draw(st.integers(0, 3)) == 0:
            argv += ["-o", pick("out")]
    if draw(st.booleans()):
        argv.append("--json")
    if draw(st.integers(0, 5)) == 0:
        argv.insert(draw(st.integers(0, len(argv))), draw(junk))
    if command != "validate" and command in ("compile", "report") and "--json" not in argv:
        argv.append("--quiet")
    return argv


def _run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exit_:  # --help / --version
            code = exit_.code
        except Exception as exc:  # noqa: BLE001 - anything escaping main is a bug
            raise AssertionError("main() raised:\n" + "".join(
                traceback.format_exception(exc))) from exc
    return code, out.getvalue(), err.getvalue()


@budget(1.0)
@given(st.data())
def test_cli_argument_vectors(files, data) -> None:
    argv = data.draw(argvs(files))
    note(repr(argv))
    code, out, err = _run(argv)
    note(f"exit {code}\nstdout: {out[-2000:]}\nstderr: {err[-2000:]}")
    assert "Traceback" not in out + err
    assert code in (0, 1, 2), code
    # validate checks every file: one error line (or JSON object) per bad file
    each_file = code == 1 and argv[:1] == ["validate"]
    if code in (1, 2):  # a runtime or a usage error: one line either way
        if "--json" in argv and each_file:  # every bad file's object names it
            docs = [json.loads(x) for x in out.strip().splitlines()]
            bad = [d for d in docs if d.get("ok") is False]
            assert bad and all(set(d) == {"chain", "file", "ok", "error", "type", "node"}
                               for d in bad), out
        elif "--json" in argv:
            line = out.strip().splitlines()[-1]
            assert set(json.loads(line)) == {"error", "type", "node"}
        else:
            lines = [x for x in err.splitlines() if x.strip()]
            assert lines and all(x.startswith("error: ") for x in lines), err
            assert len(lines) == 1 or (each_file and len(lines) <= len(argv)), err
