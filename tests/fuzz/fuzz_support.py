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
import resource
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


def bounded_outcome(call: Callable[[], Any], culprits: Iterable[str],
                    max_growth: int = 1 << 30) -> Any:
    """:func:`outcome`, and the process's peak memory may grow by at most ``max_growth``
    bytes meanwhile (a forged header that makes a reader allocate gigabytes fails here even
    when the read ends in a proper error)."""
    before = peak_rss()
    result = outcome(call, culprits)
    growth = peak_rss() - before
    assert growth <= max_growth, f"peak memory grew by {growth} bytes"
    return result


def peak_rss() -> int:
    """The process's peak resident memory so far, bytes (``ru_maxrss`` is in KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def expect_radarsnn_error(err: RadarSNNError, culprits: Iterable[str]) -> None:
    """The message is one non-empty text naming a culprit, and ``err.node`` if set."""
    message = str(err)
    assert message.strip(), f"{type(err).__name__} with an empty message"
    names = [c for c in culprits if c]
    assert any(c in message for c in names), (
        f"{type(err).__name__} names none of {names[:12]}: {message}")
    if err.node is not None:  # named as it is, or as its repr escapes it (U+202E, newlines)
        node = str(err.node)
        assert node in message or repr(node)[1:-1] in message, (
            f"node {err.node!r} not in the message: {message}")


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


# -- hostile documents: alias and nesting bombs, values no constructor builds -----------------

#: (width, levels) of "billion laughs" aliases: a few small enough to read, most refused by the
#: node count (width ** levels), the last ones by the nesting depth too (levels + 1).
LAUGHS = [(2, 3), (3, 4), (4, 6), (9, 7), (9, 9), (10, 12), (30, 9), (2, 70), (4, 100)]
#: Nesting depths around the bound (64) and far past it (libyaml stops at 1 000 itself).
DEPTHS = [10, 63, 64, 65, 200, 1000, 5000, 100_000]


def laughs(width: int, levels: int) -> str:
    """One flow-style YAML value holding ``width ** levels`` strings via ``levels`` anchors."""
    parts = ["&l0 [" + ", ".join(["lol"] * width) + "]"]
    parts += [f"&l{k} [" + ", ".join([f"*l{k - 1}"] * width) + "]" for k in range(1, levels)]
    return "[" + ", ".join(parts) + "]"


@st.composite
def yaml_bombs(draw: st.DrawFn) -> str:
    """A one-line YAML value that a bounded parser must refuse (or read, if small)."""
    kind = draw(st.sampled_from(["laughs", "laughs", "recursive", "deep", "deep_alias",
                                 "duplicate", "value"]))
    if kind == "laughs":
        return laughs(*draw(st.sampled_from(LAUGHS)))
    if kind == "recursive":
        return draw(st.sampled_from(["&r [*r]", "&r {k: *r}", "&r [1, [2, *r]]",
                                     "[&r [1], *r, &s [*s]]"]))
    if kind == "deep":
        depth = draw(st.sampled_from(DEPTHS))
        return draw(st.sampled_from(["[" * depth + "]" * depth,
                                     "{a: " * depth + "1" + "}" * depth]))
    if kind == "deep_alias":  # each alias under 64 levels, the expansion deeper
        inner, outer = draw(st.sampled_from([(40, 30), (60, 10), (30, 30), (64, 1)]))
        return "[&d " + "[" * inner + "]" * inner + ", " + "[" * outer + "*d" + "]" * outer + "]"
    if kind == "duplicate":
        return draw(st.sampled_from(["{1: a, 1.0: b}", "{yes: a, true: b}", "{null: a, ~: b}",
                                     "{1: a, true: b}", "{0: a, false: b}", "{a: 1, a: 2}"]))
    return draw(st.sampled_from(["1" * 4301, "-" + "9" * 10_000, "2001-02-30", "!!bool x",
                                 "!!int 0x", "!!float x", "!!timestamp 2001", "!!binary '@@'",
                                 "2001-12-14t21:59:43.10-99:00", "!!set {a}", "!!str [1]"]))


@st.composite
def json_bombs(draw: st.DrawFn) -> str:
    """A JSON value a bounded parser must refuse (or read): deep nesting, giant integers."""
    kind = draw(st.sampled_from(["deep", "deep", "mixed", "int"]))
    depth = draw(st.sampled_from(DEPTHS))
    if kind == "deep":
        return "[" * depth + "]" * depth
    if kind == "mixed":  # brackets in strings must not count; objects count like arrays
        return '{"a": ' * depth + '"[[[{{{"' + "}" * depth
    return draw(st.sampled_from(["1" * 4301, "-" + "9" * 10_000, "1" * 4300, "1e999999"]))


#: Declared ``.npy`` shapes that must never reach an allocation unchecked.
HUGE_SHAPES = [(10**12,), (2**62, 4), (2**31, 2**31), (0, 10**18, 10**18), (-1,), (-8, 2),
               (1,) * 100, (2**29 + 1,), (3,), ()]
HUGE_DESCRS = ["<f8", "<c16", "|b1", "|O", "|V2000000000", "<U1000000000",
               "[('a', '<f8', (1000000, 1000000))]", "<f8"]


def npy_header(shape: tuple, descr: str, version: int = 1) -> bytes:
    """The magic and header of a ``.npy`` declaring ``shape`` of ``descr`` (no data)."""
    text = "{'descr': " + (descr if descr.startswith("[") else repr(descr)) + \
        f", 'fortran_order': False, 'shape': {shape!r}, }}"
    header = text.encode("latin1")
    size = 4 if version == 2 else 2
    header += b" " * (63 - (len(header) + 8 + size) % 64) + b"\n"
    return (b"\x93NUMPY" + bytes([version, 0]) + len(header).to_bytes(size, "little")
            + header)


@st.composite
def huge_npy(draw: st.DrawFn) -> tuple[bytes, int]:
    """A forged ``.npy`` and how long to make its file with a sparse tail (0: as is): a
    header declaring a huge, negative or odd shape and dtype with a few data bytes, or one
    declaring 4 GiB + 8 bytes (over the 4 GiB input limit) that a sparse file holds."""
    version = draw(st.sampled_from([1, 2]))
    if draw(st.integers(0, 4)) == 0:
        head = npy_header(((1 << 29) + 1,), "<f8", version)
        return head, len(head) + (4 << 30) + 8
    head = npy_header(draw(st.sampled_from(HUGE_SHAPES)), draw(st.sampled_from(HUGE_DESCRS)),
                      version)
    return head + bytes(draw(st.sampled_from([0, 8, 24, 64]))), 0
