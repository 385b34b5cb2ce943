"""Hardware profiles: built-ins carry the public figures, user YAML loads, errors name the field."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from compiler.hardware import BUILTIN_PROFILES, load_profile
from compiler.hardware.profile import FILE_FIELDS
from ir.errors import CompileError

ROOT = Path(__file__).resolve().parents[1]


def test_loihi_figures_from_notes():
    p = load_profile("loihi")
    assert (p.cores_per_chip, p.neurons_per_core, p.input_axons_per_core,
            p.output_axons_per_core) == (128, 1024, 4096, 4096)
    assert p.synapse_memory_bits_per_core == 16_384 * 64
    f = p.number_format
    assert (f.weight_bits, f.threshold_bits, f.delay_bits, f.max_delay_steps) == (8, 18, 6, 63)
    # Lava's and nengo-loihi's bit-accurate Loihi, in state units of 64 LSBs (act_shift = 6):
    # 24-bit state = 18 bits of units, threshold = 17-bit vth units (v > vth), bias = 13-bit
    # mantissa << 0..7 LSBs = << -6..1 units, mixed weights = +-127 << (weight_exp + 1) units
    assert (f.threshold_mantissa_bits, f.threshold_shift, f.threshold_max) == (17, 0, 2**17 - 1)
    assert (f.bias_mantissa_bits, f.bias_exponent_max, f.weight_exponent_max) == (13, 1, 8)
    assert f.state_bits == 18 and f.graded_spike_bits is None and f.per_neuron_scales
    f2 = load_profile("loihi2").number_format
    assert (f2.weight_bits, f2.state_bits, f2.graded_spike_bits) == (8, 24, 24)
    assert not p.shared_weights_per_core
    assert p.limits().tolist() == [1024, 4096, 4096, 1_048_576]


def test_other_builtins():
    assert load_profile("loihi2").neurons_per_core == 8192
    assert load_profile("spinnaker2").cores_per_chip == 152
    assert load_profile("spinnaker2").neurons_per_core == 256
    u = load_profile("unbounded")
    assert u.name == "unbounded" and u.n_cores is None and u.number_format.max_delay_steps is None
    assert np.isinf(u.limits()).all()


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_every_builtin_field_has_a_source_comment(name):
    text = (ROOT / "compiler" / "hardware" / "profiles" / f"{name}.yaml").read_text()
    fields = [ln for ln in text.splitlines() if re.match(r"^[a-z_]+:", ln)]
    assert {ln.split(":")[0] for ln in fields} == set(FILE_FIELDS)
    missing = [ln for ln in fields if "#" not in ln and not ln.startswith(("name:", "desc"))]
    assert not missing
    # the energy block's figures carry their source as data (the report prints it)
    nested = [ln for ln in text.splitlines() if re.match(r"^  [a-z_]+:", ln)]
    assert all("source:" in ln for ln in nested), [ln for ln in nested if "source:" not in ln]


def test_user_profile_file(tmp_path):
    p = load_profile(ROOT / "examples" / "profiles" / "my_chip.yaml")
    assert (p.name, p.n_cores, p.number_format.max_delay_steps) == ("my_chip", 256, 31)
    f = tmp_path / "tiny.yml"
    f.write_text("name: tiny\nunbounded: true\nneurons_per_core: 4\ncores_per_chip: 2\nchips: 1\n")
    assert load_profile(str(f)).n_cores == 2
    assert load_profile(load_profile("loihi")).name == "loihi"


def test_errors_name_the_field_and_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nneurons_per_core: 0\n")
    with pytest.raises(CompileError, match=r"bad\.yaml.*neurons_per_core.*0.*greater than"):
        load_profile(bad)
    bad.write_text("name: bad\nneurons: 3\n")
    with pytest.raises(CompileError, match="neurons.*Extra inputs"):
        load_profile(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(CompileError, match="expected a mapping"):
        load_profile(bad)
    with pytest.raises(CompileError, match="cannot be read"):
        load_profile(tmp_path / "missing.yaml")
    with pytest.raises(CompileError, match="unknown hardware profile 'tpu'"):
        load_profile("tpu")


LAUGHS = ("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
    f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
    for p, c in zip("abcdefgh", "bcdefghi", strict=True)))


@pytest.mark.parametrize(("text", "match"), [
    (LAUGHS, r"line 6: the document has more than 524288 YAML nodes"),
    ("name: x\nchips: " + "[" * 70 + "]" * 70 + "\n", "line 2: nested deeper than 64 levels"),
    ("name: x\nchips: 1\n1: a\ntrue: b\n", r"line 4: duplicate key True"),
    ("name: x\nchips: 1\nchips: 2\n", r"line 3: duplicate key 'chips'"),
])
def test_hostile_profile_files_are_compile_errors_naming_the_file(tmp_path, text, match):
    path = tmp_path / "hostile.yaml"
    path.write_text(text)
    with pytest.raises(CompileError, match=r"hardware profile file '.*hostile\.yaml': " + match):
        load_profile(path)
