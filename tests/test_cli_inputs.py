"""Command-line inputs (``-i``, ``-c``) and ``radarsnn validate`` over several files (issue 19 #7).

Exit statuses are only checked as zero / non-zero: the policy (2 usage, 1 runtime) is
documented in docs/cli.md and tested where it is set.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from ir.errors import RadarSNNError
from radarsnn.cli import main
from radarsnn.cli.arrays import load_arrays

CHAINS = Path(__file__).resolve().parents[1] / "examples" / "chains"
BAD_CHAIN = ("name: x\nnodes:\n  - {id: a, op: input, shape: {range: 8}}\n"
             "  - {id: w, op: window, input: a, axis: doppler, kind: hann}\n"
             "  - {id: o, op: output, input: w}\n")


def _artifact(folder: Path, shape: dict[str, int]) -> Path:
    """A one-neuron network that spikes when the inputs sum to 2 (port ``x``, output ``y``)."""
    from backends import save
    from compiler.snn import (
        Decoder,
        Encoder,
        LatencyCode,
        MatrixProjection,
        NeuronParams,
        Population,
        SpikingNetwork,
    )

    size = int(np.prod(list(shape.values())))
    net = SpikingNetwork(
        name="tiny", n_steps=8,
        populations=[Population(id="in", shape=shape, source=True),
                     Population(id="out", shape={"o": 1},
                                params=NeuronParams(v_th=2.0, reset="fire_once"))],
        projections=[MatrixProjection(id="w", source="in", target="out",
                                      contract=tuple(shape), produce=("o",),
                                      weights=np.ones((size, 1)))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="y", population="out", kind="spiked")])
    save(net, folder)
    return folder


def _run(art: Path, *inputs: str, extra: tuple[str, ...] = ()) -> list[str]:
    argv = ["run", str(art), "--mode", "step", "--json"]
    for item in inputs:
        argv += ["-i", item]
    return argv + list(extra)


def test_a_port_given_twice_is_refused_in_one_line(tmp_path, capsys):
    art = _artifact(tmp_path / "art", {"i": 2})
    np.save(tmp_path / "x.npy", np.ones(2))
    x = str(tmp_path / "x.npy")
    assert main(["run", str(art), "-i", f"x={x}", "-i", f"x={x}"]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ")
    assert "input port 'x' is given twice" in err and "give each port once" in err
    with pytest.raises(RadarSNNError, match="given twice"):  # a bare file names the port too
        load_arrays([x, f"x={x}"], ["x"], "artifact a")


def test_run_outputs_read_back_as_inputs(tmp_path, capsys):
    art = _artifact(tmp_path / "art", {"i": 2})
    np.save(tmp_path / "x.npy", np.ones(2))
    assert main(_run(art, str(tmp_path / "x.npy"), extra=("-o", str(tmp_path / "out")))) == 0
    capsys.readouterr()
    # the only array of out.npz, or by key
    for spec in (f"x={tmp_path / 'out.npz'}", f"x={tmp_path / 'out.npz'}:y"):
        assert load_arrays([spec], ["x"], "artifact a")["x"].tolist() == [1.0]
    np.savez(tmp_path / "in.npz", a=np.ones(2), b=np.zeros(2))
    assert main(_run(art, f"{tmp_path / 'in.npz'}:a")) == 0
    assert json.loads(capsys.readouterr().out)["spike_counts"]["out"] == 1
    assert main(_run(art, f"{tmp_path / 'in.npz'}:b")) == 0
    assert json.loads(capsys.readouterr().out)["spike_counts"]["out"] == 0
    assert main(["run", str(art), "-i", str(tmp_path / "in.npz")]) != 0
    err = capsys.readouterr().err
    assert "holds 2 arrays ('a', 'b')" in err and "FILE.npz:NAME" in err


def test_mat_inputs_by_variable(tmp_path, capsys):
    art = _artifact(tmp_path / "art", {"i": 2})
    savemat(tmp_path / "in.mat", {"chirp": np.ones(2), "other": np.zeros(3)})
    assert main(_run(art, f"x={tmp_path / 'in.mat'}:chirp")) == 0
    assert json.loads(capsys.readouterr().out)["spike_counts"]["out"] == 1
    assert main(["run", str(art), "-i", f"x={tmp_path / 'in.mat'}:nope"]) != 0
    assert "has no variable 'nope'; its variables are 'chirp', 'other'" in capsys.readouterr().err


def test_ti_bin_inputs_with_a_layout(tmp_path, capsys):
    art = _artifact(tmp_path / "art", {"rx": 1, "chirp": 1, "sample": 2})
    np.array([1, 1], dtype="<i2").tofile(tmp_path / "cap.bin")  # one real frame
    layout = "samples=2,chirps=1,rx=1,real"
    assert main(_run(art, str(tmp_path / "cap.bin"), extra=("--bin-layout", layout))) == 0
    assert json.loads(capsys.readouterr().out)["spike_counts"]["out"] == 1
    # two frames: a leading frame axis
    np.array([1, 1, 0, 0], dtype="<i2").tofile(tmp_path / "two.bin")
    frames = load_arrays([str(tmp_path / "two.bin")], ["x"], "a", bin_layout=layout)["x"]
    assert frames.shape == (2, 1, 1, 2)
    assert main(["run", str(art), "-i", str(tmp_path / "cap.bin")]) != 0
    assert "is a raw TI capture: give its layout, e.g. --bin-layout" in capsys.readouterr().err
    assert main(["run", str(art), "-i", str(tmp_path / "cap.bin"), "--bin-layout",
                 "samples=3,chirps=1,rx=1,real"]) != 0
    err = capsys.readouterr().err
    assert "cap.bin holds 4 bytes, not a multiple of one frame's 6 bytes" in err
    np.save(tmp_path / "x.npy", np.ones((1, 1, 2)))
    assert main(["run", str(art), "-i", str(tmp_path / "x.npy"), "--bin-layout", layout]) != 0
    assert "no input is a .bin capture" in capsys.readouterr().err


def test_validate_checks_every_file_and_names_the_bad_ones(tmp_path, capsys):
    good = str(CHAINS / "ti_range.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD_CHAIN)
    missing = tmp_path / "missing.yaml"
    argv = ["validate", good, str(bad), str(missing), good]
    assert main(argv) != 0
    out, err = capsys.readouterr()
    assert out.count("is valid") == 2  # the file after the bad ones is checked too
    lines = err.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith(f"error: {bad}: ") and "'w'" in lines[0]
    assert lines[1].startswith(f"error: {missing}: ")
    assert main(["validate", good, good]) == 0


def test_validate_json_errors_carry_the_file(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD_CHAIN)
    good = str(CHAINS / "ti_range.yaml")
    assert main(["validate", str(bad), good, "--json"]) != 0
    docs = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [d["ok"] for d in docs] == [False, True]
    assert docs[0]["file"] == str(bad) and docs[0]["node"] == "w"
    assert docs[0]["type"] == "IRError" and "doppler" in docs[0]["error"]


def test_every_argument_of_every_command_has_help_text():
    """``radarsnn COMMAND --help`` explains every positional and option (``run --mode`` did not)."""
    import argparse

    from radarsnn.cli import build_parser

    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    bare = [f"{name} {a.option_strings[0] if a.option_strings else a.dest}"
            for name, p in [("radarsnn", parser), *sub.choices.items()] for a in p._actions
            if not a.help and not isinstance(a, argparse._HelpAction)]
    assert not bare, f"arguments without help: {bare}"


def test_bin_layout_takes_the_python_field_names_too(tmp_path):
    """``--bin-layout`` accepts ``TiBinLayout``'s own names (``n_samples=``) as well."""
    from radar.ti_capture import TiBinLayout

    short = TiBinLayout.parse("samples=8,chirps=2,rx=4,tx=2,real,bits=12")
    assert TiBinLayout.parse("n_samples=8,n_chirps=2,n_rx=4,n_tx=2,complex=false,"
                             "adc_bits=12") == short
    assert short == TiBinLayout(n_samples=8, n_chirps=2, n_rx=4, n_tx=2, complex=False,
                                adc_bits=12)


def test_read_ti_bin_is_4d_unless_squeezed(tmp_path):
    from radar.ti_capture import TiBinLayout, read_ti_bin

    layout = TiBinLayout(n_samples=4, n_chirps=2, n_rx=1)
    np.arange(2 * layout.words_per_frame, dtype="<i2").tofile(tmp_path / "adc.bin")
    assert read_ti_bin(tmp_path / "adc.bin", layout).shape == (2, 1, 2, 4)
    assert read_ti_bin(tmp_path / "adc.bin", layout, squeeze=True).shape == (2, 1, 2, 4)
    one = read_ti_bin(tmp_path / "adc.bin", layout, n_frames=1)
    assert one.shape == (1, 1, 2, 4)
    assert read_ti_bin(tmp_path / "adc.bin", layout, n_frames=1, squeeze=True).shape == (1, 2, 4)


def test_version_imports_no_command_module():
    """``radarsnn --version`` took 2.1 s importing every sub-command's stack (numpy, scipy …)."""
    import subprocess
    import sys

    code = ("import sys\nfrom radarsnn.cli import main\ntry:\n    main(['--version'])\n"
            "except SystemExit as e:\n    assert e.code == 0\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'pydantic', 'yaml', 'matplotlib', "
            "'radarsnn.cli.chain') if m in sys.modules))")
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=root, env={**__import__("os").environ, "PYTHONPATH": str(root)},
                          check=True)
    assert done.stdout.splitlines() == [done.stdout.splitlines()[0], "[]"]
    assert done.stdout.startswith("radarsnn ")


def test_each_command_is_added_by_the_module_main_imports_for_it():
    import argparse

    from radarsnn.cli import COMMANDS, build_parser

    def commands(parser):
        (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        return list(sub.choices)

    assert commands(build_parser()) == list(COMMANDS)  # every command, in the table's order
    for name, load in COMMANDS.items():
        assert name in commands(build_parser([load()]))
        assert load().__name__.startswith("radarsnn.cli.")
