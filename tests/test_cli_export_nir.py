"""``radarsnn export-nir`` (radarsnn.cli.export_nir): chain files, compiled folders, network
artifacts, the export report beside the file, one-line errors, and the missing extra."""

from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest

from radarsnn.cli import build_parser, main

CHAIN = """name: tiny-range-cfar
nodes:
  - {id: x, op: input, shape: {sample: 32}}
  - {id: rng, op: dft, input: x, axis: sample, out_axis: range, keep: positive}
  - {id: mag, op: magnitude, input: rng, kind: square}
  - {id: det, op: cfar, input: mag, kind: os, guard: 1, train: 2, k: 3, alpha: 4.0}
  - {id: out, op: output, input: det}
"""


@pytest.fixture
def chain(tmp_path):
    """A small range-CFAR chain file and four calibration frames."""
    path = tmp_path / "tiny.yaml"
    path.write_text(CHAIN)
    np.save(tmp_path / "frames.npy", np.random.default_rng(0).standard_normal((4, 32)))
    return path, tmp_path / "frames.npy"


def test_the_command_is_registered():
    parser = build_parser()
    args = parser.parse_args(["export-nir", "c.yaml", "-o", "c.nir"])
    assert args.command == "export-nir" and args.target is None and args.stage is None


def test_a_chain_is_compiled_and_written_with_its_report(chain, tmp_path, capsys):
    nir = pytest.importorskip("nir")
    path, frames = chain
    out = tmp_path / "nested" / "tiny.nir"
    assert main(["export-nir", str(path), "-c", f"x={frames}", "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["nir"] == str(out) and summary["calibration"] == "calibrated on the given inputs"
    graph = nir.read(out)
    assert len(graph.nodes) == summary["nodes"] and summary["nodes"] > 0
    report = json.loads((tmp_path / "nested" / "tiny.report.json").read_text())
    assert report["path"] == str(out) and report["counts"] == summary["counts"]
    assert {"rng", "det"} <= {n.split(".")[1] for n in graph.nodes}  # n<k>.<IR node>.…


def test_a_compiled_folder_is_exported_by_stage(chain, tmp_path, capsys):
    nir = pytest.importorskip("nir")
    path, frames = chain
    assert main(["compile", str(path), "-c", str(frames), "-o", str(tmp_path / "art"), "-q"]) == 0
    capsys.readouterr()
    out = tmp_path / "cfar.nir"
    assert main(["export-nir", str(tmp_path / "art"), "--stage", "det", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.startswith(f"wrote {out} (") and "calibrated on the given inputs" in text
    assert "NIR export:" in text
    assert all(name.startswith("det.") for name in nir.read(out).nodes)


def test_a_network_artifact_is_exported(tmp_path, capsys):
    nir = pytest.importorskip("nir")
    from test_nir_export import _zoo

    from backends import save
    from backends.nir.export import export_network

    save(_zoo(), tmp_path / "zoo")
    out = tmp_path / "zoo.nir"
    assert main(["export-nir", str(tmp_path / "zoo"), "-o", str(out), "-q"]) == 0
    assert capsys.readouterr().out == ""
    assert sorted(nir.read(out).nodes) == sorted(export_network(_zoo())[0].nodes)


@pytest.mark.parametrize("extra, expected", [
    (["-c", "x.npy"], r"already compiled: -c/--calibration apply to a chain file only"),
    (["--target", "spinnaker2"], r"compiled for loihi2, not spinnaker2: export the chain file"),
    (["--stage", "nope"], r"no spiking network to export"),
])
def test_errors_are_one_line(chain, tmp_path, capsys, extra, expected):
    pytest.importorskip("nir")
    path, frames = chain
    assert main(["compile", str(path), "-c", str(frames), "-o", str(tmp_path / "art"), "-q"]) == 0
    capsys.readouterr()
    status = main(["export-nir", str(tmp_path / "art"), *extra, "-o", str(tmp_path / "o.nir")])
    err = capsys.readouterr().err
    assert status != 0 and len(err.strip().splitlines()) == 1
    assert err.startswith("error: ") and re.search(expected, err)
    assert not (tmp_path / "o.nir").exists()


def test_a_resonator_chain_is_refused_naming_the_node_the_reason_and_the_fix(chain, tmp_path,
                                                                              capsys):
    """NIR has no resonate-and-fire neuron: one typed line, nothing written."""
    pytest.importorskip("nir")
    path, frames = chain
    out = tmp_path / "r.nir"
    assert main(["export-nir", str(path), "-c", f"x={frames}", "-m", "rng=resonator",
                 "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith("error: node 'rng' (")
    assert "NIR has no resonate-and-fire neuron" in err and "--motif rng=time" in err
    assert not out.exists() and not out.with_suffix(".report.json").exists()


def test_without_nir_the_error_names_the_extra(chain, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "nir", None)  # `import nir` raises ImportError
    path, _ = chain
    assert main(["export-nir", str(path), "-o", str(tmp_path / "t.nir")]) != 0
    err = capsys.readouterr().err
    assert err == "error: radarsnn export-nir needs the nir package: pip install 'radarsnn[nir]'\n"


def test_dt_defaults_to_the_target_profiles_step(chain, tmp_path, capsys):
    pytest.importorskip("nir")
    from backends.nir import read_nir

    path, frames = chain
    out = tmp_path / "tiny.nir"
    assert main(["export-nir", str(path), "-c", f"x={frames}", "-o", str(out), "-q"]) == 0
    assert float(read_nir(out).metadata["radarsnn_dt_s"]) == 1e-05  # loihi2's time_step_s
    assert main(["export-nir", str(path), "-c", f"x={frames}", "-o", str(out), "-q",
                 "--dt-s", "0.5"]) == 0
    assert float(read_nir(out).metadata["radarsnn_dt_s"]) == 0.5


def test_import_nir_writes_artifacts_that_run_like_the_exported_ones(chain, tmp_path, capsys):
    pytest.importorskip("nir")
    from backends import load
    from backends.reference import run_program, simulate

    path, frames = chain
    assert main(["compile", str(path), "-c", str(frames), "-o", str(tmp_path / "art"), "-q"]) == 0
    assert main(["export-nir", str(tmp_path / "art"), "-o", str(tmp_path / "all.nir"), "-q"]) == 0
    capsys.readouterr()
    assert main(["import-nir", str(tmp_path / "all.nir"), "-o", str(tmp_path / "back"),
                 "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["artifacts"]
    program = load(tmp_path / "art")
    result = run_program(program, {"x": np.load(frames)[2]})
    spiking = [s.network for s in program.segments if s.kind == "spiking"]
    assert [r["artifact"] for r in rows] == [str(tmp_path / "back" / f"n{k}")
                                             for k in range(len(spiking))]
    for row, sim in zip(rows, result.simulations, strict=True):
        net = load(row["artifact"])
        again = simulate(net, {e.node or e.port: result.values[e.node or e.port]
                               for e in net.encoders})
        for port, value in sim.outputs.items():
            np.testing.assert_array_equal(again.outputs[port], value)
    bad = tmp_path / "bad.nir"
    bad.write_bytes(b"\x89HDF\r\n")
    assert main(["import-nir", str(bad), "-o", str(tmp_path / "x")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: NIR file") and "\n" not in err


def test_import_nir_reads_another_tools_graph_with_its_step(tmp_path, capsys):
    nir = pytest.importorskip("nir")
    from backends import load

    graph = nir.NIRGraph.from_list(nir.Linear(weight=np.full((2, 3), 0.5)),
                                   nir.IF(r=np.full(2, 1e3), v_threshold=np.ones(2),
                                          v_reset=np.zeros(2)))
    nir.write(tmp_path / "other.nir", graph)
    assert main(["import-nir", str(tmp_path / "other.nir"), "-o", str(tmp_path / "x")]) == 1
    assert "pass dt_s (--dt-s)" in capsys.readouterr().err
    assert main(["import-nir", str(tmp_path / "other.nir"), "-o", str(tmp_path / "net"),
                 "--dt-s", "1e-3", "--n-steps", "16", "-q"]) == 0
    net = load(tmp_path / "net")
    assert net.n_steps == 16 and net.projections[0].weights.tolist() == [[0.5, 0.5]] * 3
