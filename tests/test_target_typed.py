"""The target is one typed record end to end: a profile's number format, NO_TARGET, loaded once.

* A profile file stays flat; the loaded profile carries its number format as one record
  (``profile.number_format``) and serialises flat again, in the file's field order, so a
  saved program's target is unchanged.
* ``compile_graph`` loads the target once and every pass and lowering rule reads the same
  :class:`~compiler.hardware.HardwareProfile`; ``target=None`` lowers for ``NO_TARGET``.
* No lowering module or pass reads the target by ``getattr`` or loads it again.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

import compiler.hardware.loading as loading
from compiler.compile import compile_graph
from compiler.hardware import NO_TARGET, HardwareProfile, NumberFormat, load_profile
from compiler.hardware.number_format import NUMBER_FORMAT_FIELDS
from compiler.hardware.profile import FILE_FIELDS, REQUIRED_FIELDS
from compiler.lowering.stage_gains import gain_mechanism
from compiler.passes import CompileContext
from ir import Graph
from ir.errors import BudgetError, CompileError

ROOT = Path(__file__).resolve().parents[1]

CHAIN = {"name": "x", "nodes": [
    {"id": "adc", "op": "input", "shape": {"range": 16}},
    {"id": "f", "op": "dft", "input": "adc", "axis": "range"},
    {"id": "m", "op": "magnitude", "input": "f"},
    {"id": "o", "op": "output", "input": "m"}]}


@pytest.mark.parametrize("name", ["loihi", "loihi2", "spinnaker2", "unbounded"])
def test_the_number_format_is_the_files_flat_fields(name):
    text = (ROOT / "compiler" / "hardware" / "profiles" / f"{name}.yaml").read_text()
    doc = yaml.safe_load(text)
    profile = load_profile(name)
    fmt = profile.number_format
    assert isinstance(fmt, NumberFormat)
    assert {k: getattr(fmt, k) for k in NUMBER_FORMAT_FIELDS} == {
        k: doc[k] for k in NUMBER_FORMAT_FIELDS}
    dumped = profile.model_dump()
    assert "number_format" not in dumped  # saved flat, as the file has it
    assert list(dumped) == [k for k in FILE_FIELDS if k in dumped]  # the order saved before
    assert HardwareProfile.model_validate(dumped) == profile


def test_loihi_number_format_limits():
    fmt = load_profile("loihi").number_format
    # 17-bit vth in 64-LSB state units; 13-bit bias mantissa << 1; 6-bit delays
    assert (fmt.threshold_max, fmt.bias_max, fmt.max_delay_steps) == (2**17 - 1, 4095 * 2, 63)
    assert fmt.integer and fmt.state_width == 18
    assert NumberFormat().state_width == 24 and not NumberFormat().integer


def test_number_format_flat_or_nested_not_both():
    nested = HardwareProfile(name="n", number_format=NumberFormat(weight_bits=8))
    flat = HardwareProfile(name="n", weight_bits=8)
    assert nested == flat and flat.number_format.weight_bits == 8
    with pytest.raises(ValueError, match="flat .*weight_bits.* or as 'number_format', not both"):
        HardwareProfile(name="n", weight_bits=8, number_format={"state_bits": 24})


def test_a_flat_copy_updates_and_checks_the_number_format():
    loihi = load_profile("loihi")
    wider = loihi.model_copy(update={"state_bits": 20, "max_steps_per_frame": 9})
    assert (wider.number_format.state_bits, wider.max_steps_per_frame) == (20, 9)
    assert wider.number_format.weight_bits == 8 and loihi.number_format.state_bits == 18
    with pytest.raises(ValueError, match="graded_spike_bits"):
        loihi.model_copy(update={"graded_spike_bits": 1})


def test_a_bad_number_format_field_in_a_file_is_named_flat(tmp_path):
    text = (ROOT / "compiler" / "hardware" / "profiles" / "loihi.yaml").read_text()
    path = tmp_path / "p.yaml"
    path.write_text(text.replace("state_bits: 18 ", "state_bits: 1  "))
    with pytest.raises(CompileError, match=r"p\.yaml.*field 'state_bits' = 1: .*greater than"):
        load_profile(path)


def test_file_fields_are_the_profiles_fields():
    fields = {*HardwareProfile.model_fields, *NUMBER_FORMAT_FIELDS} - {"number_format"}
    assert len(FILE_FIELDS) == len(set(FILE_FIELDS)) and set(FILE_FIELDS) == fields


def test_required_fields_keep_the_file_order():
    assert REQUIRED_FIELDS[:9] == ("cores_per_chip", "chips", "neurons_per_core",
                                   "input_axons_per_core", "output_axons_per_core",
                                   "synapse_memory_bits_per_core", "bits_per_synapse",
                                   "weight_bits", "threshold_bits")
    assert set(NUMBER_FORMAT_FIELDS) <= set(REQUIRED_FIELDS)


def test_none_is_no_profile():
    with pytest.raises(CompileError, match="profile name, a YAML path or a HardwareProfile; "
                                           "got NoneType None"):
        load_profile(None)
    from compiler.passes.quantize import quantize
    from compiler.program import CompiledProgram

    assert CompiledProgram(graph=Graph.from_dict(CHAIN)).sized_for == load_profile("unbounded")
    assert quantize.__defaults__ == ("unbounded",)  # by name, not None


def test_the_context_holds_a_loaded_profile_never_none():
    assert CompileContext().target is NO_TARGET
    assert CompileContext(target="loihi").target == load_profile("loihi")
    with pytest.raises(CompileError, match="target=None.*NO_TARGET"):
        CompileContext(target=None)


def test_no_target_lowers_as_an_ideal_chip():
    fmt = NO_TARGET.number_format
    assert NO_TARGET.limits().tolist() == [float("inf")] * 4 and NO_TARGET.n_cores is None
    assert not fmt.integer and fmt.per_neuron_scales and fmt.graded_spike_bits is None
    assert (NO_TARGET.reset, NO_TARGET.fire_once, NO_TARGET.full_voltage_decay) == (
        "programmable", "programmable", True)
    # stage gains 'auto' with exact weights scale the weight columns; with integer weights
    # and per-neuron scales (the option's weight_bits on no target) they go to the neurons
    from compiler.lowering.options import TimeDftOptions

    class Ctx:
        target = NO_TARGET

        def __init__(self, **given):
            self.given = given

        def settings_of(self, model):
            return TimeDftOptions(**self.given) if model is TimeDftOptions else model()

    assert gain_mechanism(Ctx(stage_gains="auto")) == "weights"
    assert gain_mechanism(Ctx(stage_gains="auto", weight_bits=8)) == "neurons"


def test_compile_loads_the_target_once(monkeypatch):
    calls = []
    real = loading._from_text
    monkeypatch.setattr(loading, "_from_text", lambda text, label: calls.append(label)
                        or real(text, label))
    g = Graph.from_dict(CHAIN)
    bounds = {"input_bounds": {"adc": 1.0}}
    program = compile_graph(g, "loihi2", options=bounds)
    assert calls == ["built-in profile 'loihi2'"]
    assert isinstance(program.target, HardwareProfile) and program.target.name == "loihi2"
    calls.clear()
    assert compile_graph(g, None, options=bounds).target is None
    assert calls == []  # no target: no file read


def test_max_steps_per_frame_is_enforced_by_the_profile():
    tiny = load_profile("loihi2").model_copy(update={"max_steps_per_frame": 10})
    with pytest.raises(BudgetError, match=r"steps per frame .* max_steps_per_frame = 10 of "
                                          r"loihi2"):
        compile_graph(Graph.from_dict(CHAIN), tiny, motifs={"f": "time", "m": "host"},
                      options={"input_bounds": {"adc": 1.0}})


def test_no_lowering_rule_or_pass_reads_the_target_untyped():
    pattern = re.compile(r"getattr\((ctx\.)?target\b|load_profile\(ctx\.target\)|"
                         r"ctx\.target is None|target: Any")
    found = [f"{p.relative_to(ROOT)}:{n}" for folder in ("lowering", "passes")
             for p in sorted((ROOT / "compiler" / folder).glob("*.py"))
             for n, line in enumerate(p.read_text().splitlines(), 1) if pattern.search(line)]
    assert not found
