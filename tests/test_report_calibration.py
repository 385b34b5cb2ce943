"""What a report depends on without ``-c`` (docs/cli.md, *Calibration*; radarsnn.cli.notes).

Calibrated on synthetic noise, a spiking OS-CFAR on a range-Doppler power map gets a
narrow log-code range, hence a CUT delay beyond loihi2's 63 steps, relayed through
``delay_relay`` populations: more neurons than with a calibration frame holding a
target.  ``radarsnn report`` says so in its note, and a compiled folder keeps it.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from radarsnn.cli import main

CHAIN = """name: small-rd-oscfar
nodes:
- {id: adc, op: adc_input, shape: {rx: 8, chirp: 16, sample: 32}, complex: true}
- {id: rng, op: dft, input: adc, axis: sample, out_axis: range}
- {id: dop, op: dft, input: rng, axis: chirp, out_axis: doppler, shift: true}
- {id: mag, op: magnitude, input: dop, kind: square}
- {id: rd, op: sum, input: mag, axis: rx}
- {id: det, op: cfar, input: rd, kind: os, axes: [range, doppler], guard: [1, 1], train: [4, 2],
   pfa: 1.0e-6, k: 36, edge: [clip, wrap]}
- {id: out, op: output, input: det}
"""


@pytest.fixture
def chain(tmp_path):
    """The chain file and a calibration frame: one strong target in complex noise."""
    path = tmp_path / "rd.yaml"
    path.write_text(CHAIN)
    s, c = np.arange(32), np.arange(16)
    target = 300 * np.exp(2j * np.pi * (0.2 * s[None, None, :] + 0.1 * c[None, :, None]))
    rng = np.random.default_rng(1)
    frame = target + rng.standard_normal((8, 16, 32)) + 1j * rng.standard_normal((8, 16, 32))
    np.save(tmp_path / "frame.npy", frame)
    return path, tmp_path / "frame.npy"


def _report(capsys, *argv: str) -> tuple[dict, str]:
    assert main(["report", *argv, "--json", "-q"]) == 0
    out = capsys.readouterr()
    return json.loads(out.out), out.err


def test_resources_depend_on_the_calibration_through_delay_relays(chain, capsys):
    path, frame = chain
    noise, noise_err = _report(capsys, str(path))
    given, given_err = _report(capsys, str(path), "-c", f"adc={frame}")
    motifs = {r["motif"] for r in noise["stages"] if r["node"] == "det"}
    assert motifs == {"delay_relay+time"}  # the CUT delay is relayed on noise ...
    assert {r["motif"] for r in given["stages"] if r["node"] == "det"} == {"time"}  # ... not here
    assert noise["totals"]["neurons"] > given["totals"]["neurons"]
    assert "delay_relay" in noise_err and "synthetic noise" in noise_err  # the JSON's caveat
    assert given_err == ""


def test_the_markdown_report_and_the_compiled_folder_carry_the_note(chain, tmp_path, capsys):
    path, frame = chain
    assert main(["report", str(path), "-q"]) == 0
    tail = capsys.readouterr().out.strip().splitlines()[-1]
    assert "calibrated on synthetic noise" in tail and "delay_relay" in tail and "-c" in tail
    assert main(["compile", str(path), "-q", "-o", str(tmp_path / "noise")]) == 0
    assert main(["compile", str(path), "-q", "-c", str(frame), "-o", str(tmp_path / "cal")]) == 0
    capsys.readouterr()
    assert main(["report", str(tmp_path / "noise")]) == 0
    tail = capsys.readouterr().out.strip().splitlines()[-1]
    assert tail.startswith("_from the compiled artifact, calibrated on synthetic noise")
    assert main(["report", str(tmp_path / "cal")]) == 0
    tail = capsys.readouterr().out.strip().splitlines()[-1]
    assert tail == "_from the compiled artifact, calibrated on the given inputs._"


def test_the_docs_no_longer_claim_exact_resources_either_way():
    from pathlib import Path

    cli = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text(encoding="utf-8")
    assert "exact either way" not in cli
    assert "delay_relay" in cli and "round to zero" in cli
