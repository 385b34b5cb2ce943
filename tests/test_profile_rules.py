"""Profile files say every budget on purpose: a field left out is an error unless the file
says ``unbounded: true``; counts are integers (not ``true``, not ``1.0``); and the profile's
``max_steps_per_frame`` is a budget the compile enforces."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml

from compiler.compile import compile_graph
from compiler.hardware import BUILTIN_BOARDS, BUILTIN_PROFILES, load_profile
from compiler.hardware.profile import REQUIRED_FIELDS
from ir import Graph
from ir.errors import BudgetError, CompileError

ROOT = Path(__file__).resolve().parents[1]


def _doc(name: str, folder: str = "profiles") -> dict:
    text = resources.files("compiler.hardware").joinpath(f"{folder}/{name}.yaml").read_text()
    return yaml.safe_load(text)


def _load(tmp_path: Path, doc: dict):
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(doc))
    return load_profile(path)


def test_a_profile_of_only_a_name_is_refused_unless_it_says_unbounded(tmp_path):
    with pytest.raises(CompileError, match=r"missing profile fields cores_per_chip, chips, .*"
                                           r"'unbounded: true'"):
        _load(tmp_path, {"name": "x"})
    p = _load(tmp_path, {"name": "x", "unbounded": True})
    assert p.n_cores is None and p.limits().tolist() == [np.inf] * 4
    with pytest.raises(CompileError, match=r"field 'unbounded' = 'yes'"):
        _load(tmp_path, {"name": "x", "unbounded": "yes"})


@pytest.mark.parametrize("field", REQUIRED_FIELDS)
def test_dropping_any_budget_field_is_refused(tmp_path, field):
    doc = _doc("loihi")
    del doc[field]
    with pytest.raises(CompileError, match=rf"missing profile fields {field};"):
        _load(tmp_path, doc)
    assert _load(tmp_path, {**doc, "unbounded": True}).name == "loihi"  # on purpose


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_every_shipped_profile_gives_every_field(name):
    assert set(REQUIRED_FIELDS) <= set(_doc(name)) and "unbounded" not in _doc(name)


@pytest.mark.parametrize("name", BUILTIN_BOARDS)
def test_a_board_without_its_link_figures_is_refused(tmp_path, name):
    doc = _doc(name, "boards")
    del doc["inter_chip_latency_s"]
    with pytest.raises(CompileError, match="missing board fields inter_chip_latency_s"):
        _load(tmp_path, doc)


def test_the_example_profile_gives_every_field():
    assert load_profile(ROOT / "examples" / "profiles" / "my_chip.yaml").n_cores == 256


@pytest.mark.parametrize("field, value", [
    ("chips", True), ("cores_per_chip", True), ("cores_per_chip", 1.0), ("chips", 2.0),
    ("cores_per_chip", "4")])
def test_board_counts_are_integers(tmp_path, field, value):
    doc = {**_doc("nahuku32", "boards"), field: value}
    with pytest.raises(CompileError, match=rf"field '{field}' = .*(integer|valid)"):
        _load(tmp_path, doc)


@pytest.mark.parametrize("field, value", [
    ("chips", True), ("neurons_per_core", 1024.0), ("weight_bits", True),
    ("per_neuron_scales", 1), ("shared_weights_per_core", "yes"), ("time_step_s", True),
    ("max_steps_per_frame", 1.5)])
def test_profile_fields_are_strict(tmp_path, field, value):
    with pytest.raises(CompileError, match=rf"field '{field}' = "):
        _load(tmp_path, {**_doc("loihi"), field: value})


def test_a_duration_may_be_written_without_a_dot(tmp_path):
    path = tmp_path / "p.yaml"  # PyYAML reads 1e-5 (no dot) as a string
    text = "".join(f"{k}: {'null' if v is None else str(v).lower() if isinstance(v, bool) else v}\n"
                   for k, v in {**_doc("loihi"), "time_step_s": "1e-5"}.items())
    path.write_text(text)
    assert yaml.safe_load(text)["time_step_s"] == "1e-5"  # a string to PyYAML
    assert load_profile(path).time_step_s == 1e-5


def _small():
    graph = Graph.from_dict({"name": "small", "nodes": [
        {"id": "x", "op": "input", "shape": {"chirp": 2, "sample": 16}},
        {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
        {"id": "o", "op": "output", "input": "f"}]})
    return graph, {"x": np.random.default_rng(0).standard_normal((3, 2, 16))}


#: Neuron fields that let loihi's budgets run every motif (a hypothetical chip: the stock
#: Loihi 1 refuses the time-coded S-FT, docs/hardware.md).
PROGRAMMABLE = {"current_decay_offset_lsb": 0, "full_voltage_decay": True,
                "reset": "programmable", "fire_once": "programmable",
                "threshold_schedule": True, "input_gate": True}


def test_max_steps_per_frame_is_a_budget(tmp_path):
    graph, cal = _small()
    doc = {**_doc("loihi"), **PROGRAMMABLE, "max_steps_per_frame": 1}
    with pytest.raises(BudgetError, match=r"stage 'f' of network 'small' runs 64 steps "
                                          r"per frame .* max_steps_per_frame = 1 of loihi"):
        compile_graph(graph, _load(tmp_path, doc), calibration_inputs=cal, time_steps=32)
    fits = compile_graph(graph, _load(tmp_path, {**doc, "max_steps_per_frame": 64}),
                         calibration_inputs=cal, time_steps=32)
    assert max(r["steps_per_frame"] for r in fits.records.report.data["stages"]) == 64
