"""``--option KEY=VALUE`` reads VALUE as YAML, but YAML 1.1's boolean words (``off``, ``on``,
``yes``, ``no``) stay the words a user wrote: ``resonator_renorm=off`` is the documented
value ``'off'``, not ``False`` (no compile option is a boolean)."""

from __future__ import annotations

import pytest

from compiler.option_checks import check_options
from radarsnn.cli.compiling import parse_options


@pytest.mark.parametrize("word", ["off", "Off", "on", "yes", "no", "y", "n"])
def test_yaml_boolean_words_stay_words(word):
    assert parse_options([f"resonator_renorm={word}"]) == {"resonator_renorm": word}


def test_off_is_a_valid_renorm_value():
    options = parse_options(["resonator_renorm=off"])
    assert check_options(options) == {"resonator_renorm": "off"}  # the checker accepts it
    assert parse_options(["x=true", "y=False"]) == {"x": True, "y": False}
