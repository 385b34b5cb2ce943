"""``radarsnn compile`` / ``run`` / ``report`` on program artifacts; the CLI error contract."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from backends import load, save
from backends.reference import RunOptions, run_program
from compiler import compile_graph
from ir import Graph
from ir.errors import ArtifactError
from radarsnn.cli import main

CHAINS = Path(__file__).resolve().parents[1] / "examples" / "chains"
TI = CHAINS / "ti_range.yaml"


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    out = tmp_path_factory.mktemp("art") / "ti"
    assert main(["compile", str(TI), "--target", "loihi2", "-o", str(out), "--quiet"]) == 0
    return out


def test_compile_writes_a_program_artifact_that_runs(compiled, tmp_path, capsys):
    names = sorted(p.name for p in compiled.iterdir())
    assert names == ["networks", "program.json", "report.md"]
    program = load(compiled)
    assert [s.kind for s in program.segments][0] == "spiking" and program.target.name == "loihi2"
    rng = np.random.default_rng(0)
    x = np.cos(2 * np.pi * 40 * np.arange(1024) / 1024) + 0.01 * rng.standard_normal(1024)
    np.save(tmp_path / "x.npy", x)
    assert main(["run", str(compiled), "-i", str(tmp_path / "x.npy"), "--json",
                 "-o", str(tmp_path / "y.npz")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["outputs"] == {"out": [512]} and doc["spikes"] > 0
    direct = run_program(program, {"chirp": x}).outputs["out"]
    np.testing.assert_array_equal(np.load(tmp_path / "y.npz")["out"], direct)
    assert direct[40] == 1.0  # the tone's bin is detected
    options = RunOptions(mode="auto", out_of_range="reject")  # one record, as run_program takes
    via_options = run_program(program, {"chirp": x}, options=options)
    np.testing.assert_array_equal(via_options.outputs["out"], direct)
    assert via_options.total_spikes == doc["spikes"]


def test_same_chain_gives_byte_identical_artifacts(compiled, tmp_path):
    again = tmp_path / "again"
    assert main(["compile", str(TI), "-o", str(again), "--quiet"]) == 0
    for a in sorted(p for p in compiled.rglob("*") if p.is_file()):
        b = again / a.relative_to(compiled)
        assert a.read_bytes() == b.read_bytes(), a.name


def test_report_reads_a_compiled_artifact(compiled, capsys):
    assert main(["report", str(compiled), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["target"] == "loihi2" and doc["totals"]["neurons"] > 0
    assert main(["report", str(compiled), "--target", "loihi2", "--json"]) == 0
    capsys.readouterr()
    # another target than the artifact's: refused, naming both and the fix (was ignored)
    assert main(["report", str(compiled), "--target", "spinnaker2"]) == 1
    err = capsys.readouterr().err
    assert "compiled for loihi2" in err and "not spinnaker2" in err and "CHAIN.yaml" in err


def test_report_format_json_is_deprecated_for_json(compiled, capsys):
    assert main(["report", str(compiled), "--json"]) == 0
    fresh = capsys.readouterr()
    assert "deprecated" not in fresh.err and json.loads(fresh.out)["target"] == "loihi2"
    assert main(["report", str(compiled), "--format", "json"]) == 0  # still works, and says so
    old = capsys.readouterr()
    assert json.loads(old.out) == json.loads(fresh.out)
    assert old.err.splitlines()[0] == ("warning: --format json is deprecated and will be "
                                       "removed; use --json (the same output)")


def test_compile_json_summary(tmp_path, capsys):
    assert main(["compile", str(TI), "-o", str(tmp_path / "a"), "--json",
                 "--option", "headroom=1.5", "-m", "dft=rate"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["target"] == "loihi2" and doc["segments"][0] == "spiking"
    assert load(tmp_path / "a").options["headroom"] == 1.5
    lat = doc["latency"]  # the real-time fit, in seconds
    assert lat["frame_period_s"] == pytest.approx(0.1) and isinstance(lat["fits"], bool)
    assert lat["total_s"] == pytest.approx(lat["total_steps"] * 1e-5)  # loihi2: 10 µs a step
    energy = doc["energy"]  # loihi2: no per-operation figures; the DSP's stays
    assert energy["total_J"] is None and energy["dsp_J"] > 0


def test_compile_prints_latency_frame_period_and_fit_in_seconds(tmp_path, capsys):
    assert main(["compile", str(TI), "-o", str(tmp_path / "a")]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.strip().startswith("latency "))
    assert re.fullmatch(r"  latency [\d.e+-]+ s per frame \([\d ]+ steps x 1e-05 s\) against a "
                        r"frame period of 0\.1 s: (fits|does NOT fit.*)", line), line
    # loihi2 publishes no energy per operation: said, with the DSP figure beside it
    line = next(x for x in out.splitlines() if x.strip().startswith("energy "))
    assert re.fullmatch(r"  energy per frame on loihi2: not published \(no per-operation "
                        r"figures\); conventional DSP \(C674x\) ≈ [\d.]+ [µm]J/frame", line), line


def test_an_edited_program_artifact_is_refused(compiled, tmp_path):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(compiled, copy)
    manifest = copy / "program.json"
    manifest.write_text(manifest.read_text().replace('"loihi2"', '"loihi"', 1))
    with pytest.raises(ArtifactError, match="program.json"):
        load(copy)
    shutil.rmtree(copy)
    shutil.copytree(compiled, copy)
    arrays = copy / "networks" / "0" / "arrays.npz"
    raw = bytearray(arrays.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    arrays.write_bytes(bytes(raw))
    with pytest.raises(ArtifactError, match="arrays.npz"):
        load(copy)


def test_save_dispatches_on_programs(tmp_path):
    g = Graph.from_dict({"name": "x", "nodes": [
        {"id": "a", "op": "input", "shape": {"range": 3}},
        {"id": "o", "op": "output", "input": "a"}]})
    program = compile_graph(g, target=None)
    back = load(save(program, tmp_path / "p"))
    assert back.target is None and back.graph == g and back.records == {}


@pytest.mark.parametrize("argv, needle, status", [
    (["compile", "nope.yaml", "-o", "x"], "nope.yaml", 1),
    (["run", "missing_dir", "-i", "x.npy"], "missing_dir", 1),
    (["compile", str(TI), "-o", "x", "--target", "no-such-chip"], "no-such-chip", 1),
    (["compile", str(TI), "-o", "x", "--option", "bogus=1"], "bogus", 1),
    (["compile", str(TI), "-o", "x", "--motif", "dft"], "NODE_OR_OP=MOTIF", 2),
    (["compile", str(TI)], "--output/-o", 2),
    (["no-such-command"], "invalid choice", 2),
])
def test_errors_are_one_line_without_traceback(argv, needle, status, capsys, tmp_path,
                                               monkeypatch):
    """Exit status 2 for a bad command line, 1 for a runtime (typed) error; one line each."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == status
    err = capsys.readouterr().err
    assert err.startswith("error: ") and needle in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_json_errors_are_json(capsys, tmp_path):
    assert main(["compile", str(tmp_path / "nope.yaml"), "-o", str(tmp_path / "x"),
                 "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert "nope.yaml" in doc["error"] and doc["type"]


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(Exception, match="nope"):
        main(["--debug", "validate", str(tmp_path / "nope.yaml")])


def test_program_artifacts_keep_the_axis_order(tmp_path):
    # regression: the sorted manifest reordered {rx, chirp, sample} to {chirp, rx, sample}
    g = Graph.from_dict({"name": "order", "nodes": [
        {"id": "adc", "op": "input", "shape": {"rx": 2, "chirp": 4, "sample": 8}},
        {"id": "m", "op": "magnitude", "input": "adc", "kind": "square"},
        {"id": "o", "op": "output", "input": "m"}]})
    back = load(save(compile_graph(g), tmp_path / "p"))
    assert list(back.graph.infer_types()["adc"].axes) == ["rx", "chirp", "sample"]
    x = np.arange(64.0).reshape(2, 4, 8)
    np.testing.assert_array_equal(run_program(back, {"adc": x}).outputs["o"], x ** 2)


def test_option_values_are_parsed_within_the_yaml_bounds(capsys, tmp_path):
    bomb = "[&a [1, 1, 1, 1, 1, 1, 1, 1], " + ", ".join(
        f"&{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]"
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)) + "]"
    assert main(["compile", str(TI), "-o", str(tmp_path / "x"), "--option",
                 f"fft_radices={bomb}"]) == 1
    err = capsys.readouterr().err
    assert "option 'fft_radices': line 1: the document has more than 524288 YAML nodes" in err
    assert len(err) < 1000


@pytest.mark.parametrize("field", ["graph", "report"])
def test_deeply_nested_json_fields_of_a_program_are_refused(compiled, tmp_path, field):
    import shutil

    from backends.artifact_io import render_json
    from backends.manifest import seal

    copy = tmp_path / "copy"
    shutil.copytree(compiled, copy)
    path = copy / "program.json"
    manifest = json.loads(path.read_text())
    manifest[field] = "[" * 5000 + "]" * 5000
    del manifest["manifest_sha256"]
    path.write_bytes(render_json(seal(manifest)))  # re-signed: the parser must catch it
    with pytest.raises(ArtifactError, match=rf"program\.json: field '{field}': line 1: nested "
                                            "deeper than 64 levels"):
        load(copy)


def test_npy_inputs_declaring_more_than_the_limit_are_refused_unread(tmp_path):
    from ir.errors import RadarSNNError
    from radarsnn.cli.chain import load_arrays

    header = repr({"descr": "<f8", "fortran_order": False, "shape": ((1 << 29) + 1,)}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    head = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header
    sparse = tmp_path / "x.npy"  # 4 GiB + 8 bytes of (sparse) data: all there
    with sparse.open("wb") as f:
        f.write(head)
        f.truncate(len(head) + (4 << 30) + 8)
    with pytest.raises(RadarSNNError, match=r"\(4294967304 bytes\), over the limit of "
                                            r"4294967296 bytes; give fewer frames"):
        load_arrays([str(sparse)], ["x"], "chain")
    with pytest.raises(RadarSNNError, match="not a regular file"):
        load_arrays(["/dev/zero"], ["x"], "chain")


@pytest.mark.parametrize("ref", ["x" * 300, "networks/a\x00b"])
def test_a_network_path_the_file_system_refuses_is_an_artifact_error(compiled, tmp_path, ref):
    import shutil

    from backends.artifact_io import render_json
    from backends.manifest import seal

    copy = tmp_path / "copy"
    shutil.copytree(compiled, copy)
    path = copy / "program.json"
    manifest = json.loads(path.read_text())
    spiking = next(s for s in manifest["segments"] if s["kind"] == "spiking")
    spiking["network"]["path"] = ref  # OSError: File name too long / ValueError: NUL byte
    del manifest["manifest_sha256"]
    path.write_bytes(render_json(seal(manifest)))
    with pytest.raises(ArtifactError, match=r"program\.json: network path '.*' cannot be used"):
        load(copy)


def test_verbose_logs_each_pass_and_quiet_by_default(capsys, tmp_path):
    assert main(["compile", str(TI), "-o", str(tmp_path / "a"), "--target", "unbounded",
                 "-q"]) == 0
    assert "compiler.passes.base: pass" not in capsys.readouterr().err
    assert main(["compile", str(TI), "-o", str(tmp_path / "b"), "--target", "unbounded",
                 "-q", "-v"]) == 0
    err = capsys.readouterr().err
    for name in ("verify", "calibrate", "lower", "place", "report"):
        assert f"compiler.passes.base: pass {name}: " in err
    assert "compiler.passes.calibrate: policy static, ranges from" in err
    assert main(["-vv", "compile", str(TI), "-o", str(tmp_path / "c"), "--target", "unbounded",
                 "-q"]) == 0
    assert "compiler.passes.lower: node 'rng' -> motif" in capsys.readouterr().err
    main(["schema"])  # back to warnings only for the tests that follow
    capsys.readouterr()


def test_run_on_a_chain_file_says_to_compile_it_first(capsys, tmp_path):
    """It said '…/manifest.json: cannot read (Not a directory)'."""
    np.save(tmp_path / "x.npy", np.zeros(1024))
    assert main(["run", str(TI), "-i", str(tmp_path / "x.npy")]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (f"error: {TI} is a chain file, not a compiled artifact: compile it first "
                   f"(radarsnn compile {TI} -o DIR), then run the directory (radarsnn run DIR "
                   "-i …)")
    (tmp_path / "notes.txt").write_text("x")
    assert main(["run", str(tmp_path / "notes.txt"), "-i", str(tmp_path / "x.npy")]) == 1
    assert "is a file, not a compiled artifact directory" in capsys.readouterr().err
