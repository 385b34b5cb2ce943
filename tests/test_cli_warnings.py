"""A Python warning raised under a command (the resonator's drift warning) is one
``warning: …`` line on stderr, not Python's two-line ``file:line: Category: …`` form."""

from __future__ import annotations

import warnings

from radarsnn.cli import main

CHAIN = ("name: res\nnodes:\n  - {id: x, op: input, shape: {chirp: 2, sample: 64}}\n"
         "  - {id: f, op: dft, input: x, axis: sample, keep: positive}\n"
         "  - {id: o, op: output, input: f}\n")


def test_the_drift_warning_is_one_line(tmp_path, capsys):
    chain = tmp_path / "res.yaml"
    chain.write_text(CHAIN)
    before = warnings.showwarning
    assert main(["compile", str(chain), "--target", "loihi2", "--motif", "f=resonator",
                 "--option", "resonator_coef_bits=6", "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err.splitlines()
    drift = [line for line in err if "resonator drift bound" in line]
    assert len(drift) == 1 and drift[0].startswith("warning: node 'f': resonator drift bound")
    assert not any("Warning:" in line or line.startswith("  ") for line in err), err
    assert warnings.showwarning is before  # restored after the command
