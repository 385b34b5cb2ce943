"""Shared pieces of the fuzz suite: example budgets, the allowed-outcome check, hostile values.

Budget: every entry point runs ``EXAMPLES_PER_ENTRY_POINT`` × the profile's
``max_examples`` examples, split over its tests by share (CI profile 200 →
2 000 per entry point; ``--hypothesis-profile=deep`` 5 000 → 50 000).

The only allowed outcomes of a fuzzed call are a correct result or an exception
from ``ir.errors``' hierarchy whose message names the offending node, field or
file: :func:`expect_radarsnn_error` checks the latter.
"""

from __future__ import annotations

import copy
import math
import os
import traceback
from collections.abc import Callable, Iterable
from typing import Any

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from ir.errors import RadarSNNError

#: Examples per entry point, as a multiple of the profile's ``max_examples``.
EXAMPLES_PER_ENTRY_POINT = 10


def budget(share: float) -> settings:
    """Hypothesis settings for one test taking ``share`` of its entry point's examples."""
    n = max(1, math.ceil(EXAMPLES_PER_ENTRY_POINT * settings.default.max_examples * share))
    deadline = os.environ.get("FUZZ_DEADLINE_MS")  # find slow examples while debugging
    return settings(max_examples=n, deadline=int(deadline) if deadline else None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much,
                                           HealthCheck.function_scoped_fixture])


def outcome(call: Callable[[], Any], culprits: Iterable[str]) -> Any:
    """Run ``call``; return its result, or None after checking the error it raised.

    Raises
    ------
    AssertionError
        If ``call`` raised anything outside :class:`RadarSNNError` (with its
        traceback), or a RadarSNNError whose message names none of ``culprits``.
    """
    try:
        return call()
    except RadarSNNError as err:
        expect_radarsnn_error(err, culprits)
        return None
    except Exception as err:  # noqa: BLE001 - the point: anything else is a bug
        raise AssertionError("not a RadarSNNError:\n" + "".join(
            traceback.format_exception(err))) from err


def expect_radarsnn_error(err: RadarSNNError, culprits: Iterable[str]) -> None:
    """The message is one non-empty text naming a culprit, and ``err.node`` if set."""
    message = str(err)
    assert message.strip(), f"{type(err).__name__} with an empty message"
    names = [c for c in culprits if c]
    assert any(c in message for c in names), (
        f"{type(err).__name__} names none of {names[:12]}: {message}")
    if err.node is not None:
        assert str(err.node) in message, f"node {err.node!r} not in the message: {message}"


#: Strings that have broken parsers, paths, templates or terminals somewhere.
HOSTILE_STRINGS = [
    "", " ", "\x00", "\n", "a\nb: c", "../../etc/passwd", "/dev/zero", "C:\\nul",
    "__import__('os').system('true')", "'; drop table", "${HOME}", "{{x}}", "%s%n",
    "&a [*a, *a]", "!!python/object:os.system", "- - -", "{", "[", "]", ":", "#",
    "\u202etxt.exe", "\u2028", "ß\u0301", "\ud7ff", "日本語", "x" * 300, "1e999", "NaN",
    "-0", "0x10", "True", "null", "~",
    # PEP 263 source-encoding declarations (a generated file's lines 1-2 must never hold them)
    "coding:utf-7+AAo-open('pwned','w')+AAo-#", "# -*- Coding: rot13 -*-", "CODING=utf_16",
    "vim: set fileencoding=latin-1 :", "\ncoding:utf-7\n", '"' * 3, "'" * 3, "\\",
]

#: JSON-able junk for any field.
JUNK = st.one_of(
    st.none(), st.booleans(),
    st.sampled_from([0, -1, 1, 2, 3, 2**31, 2**63, 2**64, -(2**63), 10**30]),
    st.integers(-10, 10**6),
    st.sampled_from([0.0, -0.0, 0.5, -1.5, 1e308, -1e308, 5e-324, math.nan, math.inf,
                     -math.inf]),
    st.sampled_from(HOSTILE_STRINGS),
    st.text(max_size=12),
    st.lists(st.integers(-3, 5), max_size=4),
    st.lists(st.sampled_from(["range", "doppler", "x", "", "part"]), max_size=3),
    st.dictionaries(st.sampled_from(["a", "range", "1bad", "", "part"]),
                    st.sampled_from([-1, 0, 1, 3, 2**40, "x", None]), max_size=3),
    st.just([[1.0, 2.0], [3.0]]), st.just({}), st.just([]),
).map(copy.deepcopy)  # st.just gives one shared object: a mutation must not leak to the next


def flip_bytes(data: bytes, positions: list[int], masks: list[int]) -> bytes:
    """``data`` with the byte at each position (mod length) xor-ed with its mask (1..255)."""
    if not data:
        return data
    out = bytearray(data)
    for pos, mask in zip(positions, masks, strict=False):
        out[pos % len(out)] ^= mask
    return bytes(out)


@st.composite
def byte_mutations(draw: st.DrawFn, data: bytes) -> bytes:
    """Truncate, flip, insert, delete or duplicate bytes of ``data``."""
    kind = draw(st.sampled_from(["truncate", "flip", "insert", "delete", "duplicate", "empty"]))
    n = len(data)
    if kind == "empty" or n == 0:
        return b""
    at = draw(st.integers(0, n - 1))
    if kind == "truncate":
        return data[:at]
    if kind == "flip":
        k = draw(st.integers(1, 4))
        return flip_bytes(data, [at + draw(st.integers(0, 64)) for _ in range(k)],
                          [draw(st.integers(1, 255)) for _ in range(k)])
    if kind == "insert":
        junk = draw(st.one_of(st.binary(min_size=1, max_size=16),
                              st.sampled_from(HOSTILE_STRINGS).map(str.encode)))
        return data[:at] + junk + data[at:]
    if kind == "delete":
        return data[:at] + data[at + draw(st.integers(1, 64)):]
    end = min(n, at + draw(st.integers(1, 256)))
    return data[:end] + data[at:end] + data[end:]
