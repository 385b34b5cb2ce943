"""Fuzz: hardware profile files mutated from the built-in ones — load, then use the budgets.

Mutations: junk in any field (wrong types, NaN/Inf, zero/negative/huge counts, hostile
strings), missing and extra fields (a profile or board that loads gave every required field,
unless it said ``unbounded: true``, and every value exactly as written: no ``true`` or ``1.0``
read as a count), non-string keys, non-mapping documents,
byte-level damage (truncation, flipped and inserted bytes, binary garbage), and hostile
YAML in any field or as the document: alias bombs, recursive aliases, deep nesting, keys
equal as values, values no constructor builds.
"""

from __future__ import annotations

import tempfile
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml
from fuzz_support import JUNK, budget, byte_mutations, outcome, yaml_bombs
from hypothesis import given, note
from hypothesis import strategies as st
from pydantic import BaseModel

from compiler.hardware import BUILTIN_BOARDS, BUILTIN_PROFILES, HardwareProfile, load_profile
from compiler.hardware.boards import BOARD_REQUIRED
from compiler.hardware.number_format import NUMBER_FORMAT_FIELDS
from compiler.hardware.profile import FILE_FIELDS, REQUIRED_FIELDS

TEXTS = {name: resources.files("compiler.hardware").joinpath(f"profiles/{name}.yaml").read_text()
         for name in BUILTIN_PROFILES}
FIELDS = sorted(FILE_FIELDS)


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fuzz-profile-") as tmp:
        yield Path(tmp)


def _use(path: Path) -> HardwareProfile:
    profile = load_profile(path)
    limits = profile.limits()
    assert limits.shape == (4,) and not np.isnan(limits).any() and (limits >= 1).all()
    assert profile.n_cores is None or profile.n_cores >= 1
    max_delay = profile.number_format.max_delay_steps
    assert max_delay is None or max_delay >= 0
    assert HardwareProfile(**profile.model_dump()) == profile
    return profile


@budget(0.5)
@given(st.sampled_from(BUILTIN_PROFILES), st.data(), st.integers(0, 9))
def test_field_mutated_profiles(folder, name, data, slot) -> None:
    doc = yaml.safe_load(TEXTS[name])
    touched = []
    for _ in range(data.draw(st.integers(1, 3))):
        kind = data.draw(st.sampled_from(["set", "set", "delete", "extra", "key", "document"]))
        if kind == "set":
            key = data.draw(st.sampled_from(FIELDS))
            doc[key] = data.draw(JUNK)
        elif kind == "delete":
            key = data.draw(st.sampled_from(sorted(doc, key=str) or ["name"]))
            doc.pop(key, None)
        elif kind == "extra":
            key = data.draw(st.sampled_from(["cores", "neurons", "", "name ", "__class__"]))
            doc[key] = data.draw(JUNK)
        elif kind == "key":
            key = data.draw(st.sampled_from([1, 2.5, True, None, (1, 2)]))
            doc[key] = 1
        else:
            key = "document"
            doc = data.draw(st.one_of(JUNK, st.lists(st.just(doc), max_size=2)))
            break
        touched.append(str(key))
    path = folder / f"profile{slot}.yaml"
    path.write_text(yaml.safe_dump(doc, allow_unicode=True) if not isinstance(doc, dict) or all(
        isinstance(k, str) for k in doc) else yaml.dump(doc, allow_unicode=True))
    note(path.read_text())
    outcome(lambda: _use(path), [str(path), *touched])


@budget(0.3)
@given(st.sampled_from(BUILTIN_PROFILES), st.data(), st.integers(0, 9))
def test_byte_damaged_profiles(folder, name, data, slot) -> None:
    damaged = data.draw(byte_mutations(TEXTS[name].encode()))
    path = folder / f"damaged{slot}.yaml"
    path.write_bytes(damaged)
    note(repr(damaged))
    outcome(lambda: _use(path), [str(path)])


@budget(0.2)
@given(st.sampled_from(BUILTIN_PROFILES), st.data(), st.integers(0, 9))
def test_alias_and_nesting_bombs_in_profiles(folder, name, data, slot) -> None:
    doc = yaml.safe_load(TEXTS[name])
    key = data.draw(st.sampled_from([*FIELDS, "extra", "document"]))
    bomb = data.draw(yaml_bombs())
    if key == "document":
        text = bomb
    else:
        doc[key] = "BOMB_GOES_HERE"
        text = yaml.safe_dump(doc).replace("BOMB_GOES_HERE", bomb)
    path = folder / f"bomb{slot}.yaml"
    path.write_text(text)
    note(f"{key}: {bomb[:300]}")
    outcome(lambda: _use(path), [str(path)])


BOARD_TEXTS = {name: resources.files("compiler.hardware").joinpath(f"boards/{name}.yaml")
               .read_text() for name in BUILTIN_BOARDS}
#: Retyped values: the coercions a lax loader would accept (True as 1, 1.0 as 1, "4" as 4).
RETYPED = st.sampled_from([True, False, 1.0, 0.0, 2.5, "4", "true", "null", 1, 0, -1, None])


@budget(0.3)
@given(st.sampled_from([*BUILTIN_PROFILES, *BUILTIN_BOARDS]), st.data(), st.integers(0, 9))
def test_a_loaded_profile_is_exactly_what_the_file_says(folder, name, data, slot) -> None:
    board = name in BOARD_TEXTS
    doc = yaml.safe_load(BOARD_TEXTS[name] if board else TEXTS[name])
    keys = sorted(doc) if board else FIELDS
    for _ in range(data.draw(st.integers(1, 3))):
        kind = data.draw(st.sampled_from(["drop", "retype", "flag"]))
        if kind == "drop":
            doc.pop(data.draw(st.sampled_from(sorted(doc))), None)
        elif kind == "retype":
            doc[data.draw(st.sampled_from(keys))] = data.draw(RETYPED)
        else:
            doc["unbounded"] = data.draw(st.sampled_from([True, False, "yes", 1, None]))
    path = folder / f"rules{slot}.yaml"
    path.write_text(yaml.safe_dump(doc))
    note(path.read_text())
    profile = outcome(lambda: load_profile(path), [str(path)])
    if profile is None:
        return
    if doc.get("unbounded") is not True:  # nothing left out without saying so
        required = BOARD_REQUIRED if board else REQUIRED_FIELDS
        assert set(required) <= set(doc), sorted(set(required) - set(doc))
    for key, value in doc.items():  # every value as written: no bool or float read as a count
        if key == "unbounded":
            continue
        owner = profile.number_format if key in NUMBER_FORMAT_FIELDS else profile
        got = getattr(owner, key)
        if isinstance(got, BaseModel):  # a nested block (energy figures): as written, too
            got = got.model_dump(exclude_unset=True)
        if isinstance(got, float) and isinstance(value, str):  # PyYAML: 1e-5 is a string
            value = float(value)
        assert got == value and (type(got) is type(value) or (
            isinstance(got, float) and type(value) is int)), (key, value, got)
