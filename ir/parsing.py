"""Bounded YAML and JSON parsing: the one place file text becomes data.

Chain files, hardware profiles, sweep files, ``--option`` values, artifact manifests
and the graph and report a program artifact stores are all parsed here, so the same
bounds hold for every file:

* **Nesting**: at most :data:`MAX_DEPTH` levels of sequences/mappings (arrays/objects),
  aliases included, refused before anything recursive runs (PyYAML's composer,
  ``json.loads``, pydantic and ``repr`` would raise ``RecursionError``).
* **Size after alias expansion** (YAML): at most :data:`MAX_YAML_NODES` nodes, an alias
  counted as a copy of what it names, so a 500-byte "billion laughs" (10⁹ nodes) is
  refused by counting before it is composed; a recursive alias too.  The count also
  bounds parse time, with libyaml's C parser (``yaml.CSafeLoader``) where available.
* **Duplicate keys** are refused as *constructed* values, the way the mapping would
  merge them (``1`` and ``1.0``, ``yes`` and ``true``, ``null`` and ``~``), and values
  no constructor builds (4 301 digits, ``2001-02-30``, ``!!int 0x``) name their line.

Reading never runs code: PyYAML's safe constructor, :func:`json.loads`.  Syntax errors
stay ``yaml.YAMLError`` and ``json.JSONDecodeError`` (each caller words them); a bound
raises the caller's error class (``error=``) saying which bound, the amount and the line.

Examples
--------
>>> load_yaml("a: [1, 2]\\nb: {c: d}")
{'a': [1, 2], 'b': {'c': 'd'}}
>>> load_yaml("a: &x [1, 2]\\nb: *x")  # aliases are fine within the bounds
{'a': [1, 2], 'b': [1, 2]}
>>> load_yaml("{1: a, 1.0: b}")
Traceback (most recent call last):
...
ir.errors.ChainFileError: line 1: duplicate key 1.0 (equal to the key on line 1; YAML would \
silently keep the last one); remove one
>>> load_json('{"a": ' + "[" * 100 + "]" * 100 + "}")
Traceback (most recent call last):
...
ir.errors.ChainFileError: line 1: nested deeper than 64 levels (the limit, MAX_DEPTH); flatten \
the document
"""

from __future__ import annotations

import gc
import json
import re
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import yaml

from ir.errors import ChainFileError, RadarSNNError
from ir.model import short_repr

__all__ = ["MAX_DEPTH", "MAX_YAML_NODES", "YAML_LOADER", "json_depth", "load_json", "load_yaml"]

#: Deepest nesting of sequences/mappings (YAML) or arrays/objects (JSON) read.  The example
#: chains need 4 levels, a classifier's layers 6, artifact manifests 6, reports 4.
MAX_DEPTH = 64
#: Most YAML nodes (scalars, sequences, mappings) of one document, aliases expanded: about
#: 47 000 chain nodes (a 3.3 MiB chain file); parsing this many takes a few seconds at
#: most (docs/reliability.md).
MAX_YAML_NODES = 1 << 19
#: The PyYAML loader used: libyaml's C parser when available (about 5x faster).
YAML_LOADER: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

_Error = type[RadarSNNError]
_COLLECTION_START = (yaml.SequenceStartEvent, yaml.MappingStartEvent)
_COLLECTION_END = (yaml.SequenceEndEvent, yaml.MappingEndEvent)
_MERGE_TAG = "tag:yaml.org,2002:merge"
# a constructor's complaints about a value: int("0x"), date(2001, 2, 30), bool table miss, ...
_VALUE_ERRORS = (ValueError, TypeError, KeyError, AttributeError, OverflowError)


def load_yaml(text: str, *, error: _Error = ChainFileError) -> Any:
    """The one YAML document in ``text``, within the module's bounds.

    Parameters
    ----------
    text : str
        YAML text.
    error : type of RadarSNNError
        Raised for a bound, a duplicate key or a value that cannot be built (the
        caller adds the file name).

    Returns
    -------
    object
        Plain data (dicts, lists, str, int, float, bool, None, and PyYAML's safe
        types: dates, bytes, sets).

    Raises
    ------
    yaml.YAMLError
        Invalid YAML, several documents, an undefined alias, an unhashable key.
    RadarSNNError
        ``error``: deeper than :data:`MAX_DEPTH`, more than :data:`MAX_YAML_NODES` nodes
        after alias expansion, a recursive alias, a duplicate key, an unreadable value.

    Examples
    --------
    >>> bomb = "a: &a [x, x]\\n" + "".join(
    ...     f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}]\\n" for p, c in zip("abcdefghijk", "bcdefghijkl"))
    >>> load_yaml(bomb)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ir.errors.ChainFileError: line 10: the document has more than 524288 YAML nodes ...
    """
    with _gc_paused():
        _check_events(text, error)
        loader = _BoundedLoader(text)
        loader.error = error
        try:
            node = loader.get_single_node()
            if node is None:
                return None
            try:
                return loader.construct_document(node)
            except _VALUE_ERRORS as exc:  # a value outside any one node's constructor
                raise error(f"a value cannot be read: {exc}") from None
        except RecursionError:  # the pure-Python composer, if a bound were ever raised
            raise error(f"nested too deeply to parse (limit {MAX_DEPTH} levels); flatten the "
                        "document") from None
        finally:
            loader.dispose()


@contextmanager
def _gc_paused() -> Iterator[None]:
    """No cyclic garbage collection while a parser allocates its (acyclic) nodes: the
    collector would rescan them again and again (2-3x the parse time)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _check_events(text: str, error: _Error) -> None:
    """Refuse depth, alias expansion and recursive aliases from the event stream alone.

    Events come one by one (no recursion, nothing built), and every node's expanded
    size is counted as it closes: an alias adds the size of what it names, so the
    count stops at the bound however small the text is.
    """
    stack: list[list] = []  # per open collection: [nodes, height, anchor]
    closed: dict[str, tuple[int, int]] = {}  # anchor -> (nodes, height) of its node
    total = 0
    loader = YAML_LOADER(text)
    try:
        while loader.check_event():
            event = loader.get_event()
            if isinstance(event, _COLLECTION_START):
                total += 1
                if len(stack) >= MAX_DEPTH:
                    _too_deep(event, error)
                stack.append([1, 0, event.anchor])
                continue
            if isinstance(event, _COLLECTION_END):
                size, below, anchor = stack.pop()
                height = below + 1
            elif isinstance(event, yaml.ScalarEvent):
                size, height, anchor = 1, 0, event.anchor
                total += 1
            elif isinstance(event, yaml.AliasEvent):
                if any(entry[2] == event.anchor for entry in stack):
                    raise error(f"line {event.start_mark.line + 1}: alias *{event.anchor} "
                                "is inside the node it names (a recursive document); write "
                                "the value out instead")
                size, height = closed.get(event.anchor, (0, 0))  # undefined: the composer says
                anchor = None
                total += size
                if len(stack) + height > MAX_DEPTH:
                    _too_deep(event, error)
            else:  # stream and document start/end
                continue
            if total > MAX_YAML_NODES:
                raise error(f"line {event.start_mark.line + 1}: the document has more than "
                            f"{MAX_YAML_NODES} YAML nodes (the limit, MAX_YAML_NODES; aliases "
                            "count as copies of what they name); an alias bomb? write the "
                            "values out, or split the file")
            if anchor is not None:
                closed[anchor] = (size, height)
            if stack:
                stack[-1][0] += size
                stack[-1][1] = max(stack[-1][1], height)
    finally:
        loader.dispose()


def _too_deep(event: yaml.Event, error: _Error) -> None:
    raise error(f"line {event.start_mark.line + 1}: nested deeper than {MAX_DEPTH} levels "
                "(the limit, MAX_DEPTH); flatten the document")


class _BoundedLoader(YAML_LOADER):  # type: ignore[misc, valid-type]
    """The safe loader, refusing duplicate keys by value and naming unreadable values."""

    error: _Error = ChainFileError

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except _VALUE_ERRORS as exc:
            tag = str(node.tag).replace("tag:yaml.org,2002:", "!!")
            raise self.error(f"line {node.start_mark.line + 1}: {short_repr(node.value)} is "
                             f"not a readable {tag} value ({type(exc).__name__}: {exc})"
                             ) from None

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict:
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, int] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    line = first.get(key)
                except TypeError:  # unhashable: PyYAML's own error follows
                    continue
                here = key_node.start_mark.line + 1
                if line is not None:
                    raise self.error(f"line {here}: duplicate key {short_repr(key)} (equal to "
                                     f"the key on line {line}; YAML would silently keep the "
                                     "last one); remove one")
                first[key] = here
        return super().construct_mapping(node, deep=deep)


# -- JSON ------------------------------------------------------------------------------------

_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.S)
_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")
_STEPS = bytes.maketrans(b"[]{}", b"\x01\xff\x01\xff")  # +1 opens, -1 (int8) closes
_CHUNK = 1 << 20


def _bracket_levels(text: str):
    """The stripped text's bytes and, per chunk of its brackets, the nesting level after each."""
    data = _JSON_STRING.sub('""', text).encode("utf-8", "surrogatepass")
    steps = np.frombuffer(data.translate(None, _NOT_BRACKETS).translate(_STEPS), np.int8)
    base = 0
    chunks = []
    for start in range(0, len(steps), _CHUNK):
        levels = base + np.cumsum(steps[start:start + _CHUNK], dtype=np.int64)
        chunks.append((start, levels))
        base = int(levels[-1])
    return data, chunks


def json_depth(text: str) -> int:
    """The deepest nesting of arrays/objects in JSON text (brackets inside strings skipped).

    The brackets are counted with numpy, so a 64 MiB document takes a fraction of a second
    and nothing recursive runs.

    Examples
    --------
    >>> json_depth('{"a": [1, [2]], "b": "[[[["}'), json_depth("[]"), json_depth("3")
    (3, 1, 0)
    """
    _, chunks = _bracket_levels(text)
    return max((int(levels.max()) for _, levels in chunks), default=0)


def _line_deeper_than(text: str, limit: int) -> int:
    """The line of the first bracket nested deeper than ``limit`` (JSON strings hold no
    raw newline, so lines counted in the stripped text are the original's)."""
    data, chunks = _bracket_levels(text)
    for start, levels in chunks:
        over = np.flatnonzero(levels > limit)
        if over.size:
            marks = np.frombuffer(data.translate(bytes.maketrans(b"[]{}", b"\x01\x01\x01\x01")),
                                  np.uint8)
            at = np.flatnonzero(marks == 1)[start + int(over[0])]
            return data.count(b"\n", 0, int(at)) + 1
    return 0


def load_json(text: str, *, error: _Error = ChainFileError, **kwargs: Any) -> Any:
    """``json.loads(text, **kwargs)`` within :data:`MAX_DEPTH`.

    Raises
    ------
    json.JSONDecodeError
        Invalid JSON.
    RadarSNNError
        ``error``: nested deeper than :data:`MAX_DEPTH`, or an integer of more than
        4 300 digits (Python refuses to convert it).

    Examples
    --------
    >>> load_json('{"a": [1, "]]"]}')
    {'a': [1, ']]']}
    >>> load_json("1" * 5000)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ir.errors.ChainFileError: a number cannot be read (Exceeds the limit (4300 digits) ...
    """
    if json_depth(text) > MAX_DEPTH:
        raise error(f"line {_line_deeper_than(text, MAX_DEPTH)}: nested deeper than {MAX_DEPTH} "
                    "levels (the limit, MAX_DEPTH); flatten the document")
    try:
        with _gc_paused():
            return json.loads(text, **kwargs)
    except json.JSONDecodeError:
        raise
    except RecursionError:
        raise error(f"nested too deeply to parse (limit {MAX_DEPTH} levels); flatten the "
                    "document") from None
    except ValueError as exc:  # int("1" * 5000): over sys.get_int_max_str_digits()
        raise error(f"a number cannot be read ({exc}); write it as a float or shorten it"
                    ) from None
