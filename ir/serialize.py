"""Chain files: a graph as a YAML/JSON mapping of a name and an ordered node list.

Format::

    name: carrada-rd-oscfar            # optional, default "chain"
    nodes:                             # in any order; each node one mapping
      - {id: adc, op: adc_input, shape: {rx: 4, chirp: 64, sample: 256}, complex: true}
      - {id: win, op: window, input: adc, axis: sample, kind: hann}
      - {id: out, op: output, input: win}

Every node has an ``id`` and an ``op`` (a name in the op registry); ``input: x``
names its one input, ``inputs: [a, b]`` several; the other keys are the op's
parameters (see :mod:`ir.ops`). Writing drops parameters equal to their defaults,
so ``graph -> dict -> graph`` is exact and ``dict -> graph -> dict`` is exact up
to defaults. Reading never runs code: YAML goes through PyYAML's safe loader (libyaml's
C parser where available), JSON through ``json.loads``, both within the bounds of
:mod:`ir.parsing` (nesting depth, nodes after alias expansion); duplicate keys are
refused in both (YAML and JSON would silently keep the last one), in YAML as the
values they construct (``1`` and ``1.0``, ``yes`` and ``true``).  Files are read up to
:data:`MAX_CHAIN_FILE_BYTES`.

Examples
--------
>>> text = '''
... name: toy
... nodes:
...   - {id: x, op: input, shape: {range: 16}, domain: power}
...   - {id: det, op: threshold, input: x, value: 2.5}
...   - {id: out, op: output, input: det}
... '''
>>> g = graph_from_yaml(text)
>>> g.verify()
>>> graph_from_yaml(graph_to_yaml(g)) == g
True
>>> print(graph_to_yaml(g), end="")
name: toy
nodes:
- id: x
  op: input
  shape: {range: 16}
  domain: power
- {id: det, op: threshold, input: x, value: 2.5}
- {id: out, op: output, input: det}
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from ir.errors import ChainFileError, IRError
from ir.graph import Graph
from ir.model import describe_validation_error, is_name, short_repr
from ir.ops import OP_REGISTRY, OpRegistry
from ir.parsing import load_json, load_yaml

__all__ = [
    "describe_yaml_error",
    "load_yaml_mapping",
    "graph_from_dict",
    "graph_from_json",
    "graph_from_yaml",
    "graph_to_dict",
    "graph_to_json",
    "graph_to_yaml",
]

#: Largest chain file read: 8 MiB (a device such as /dev/zero would otherwise be read
#: forever).  With the node bound of :mod:`ir.parsing` it bounds the parse time
#: (docs/reliability.md); a 47 000-node chain is about 3.3 MiB.
MAX_CHAIN_FILE_BYTES = 8 << 20

_TOP_KEYS = ("name", "nodes")
_ENVELOPE = ("id", "op", "input", "inputs")


def graph_to_dict(graph: Graph) -> dict[str, Any]:
    """The chain-file mapping of ``graph`` (defaults left out; plain JSON-able values).

    Examples
    --------
    >>> from ir.ops import Input, Output
    >>> g = Graph("g")
    >>> g.add(Output(), inputs="x", id="out")
    'out'
    >>> g.add(Input(shape={"a": 2}), id="x")
    'x'
    >>> graph_to_dict(g)
    {'name': 'g', 'nodes': [{'id': 'out', 'op': 'output', 'input': 'x'}, \
{'id': 'x', 'op': 'input', 'shape': {'a': 2}}]}
    """
    nodes = []
    for id in graph:
        op, inputs = graph.op(id), graph.inputs_of(id)
        entry: dict[str, Any] = {"id": id, "op": op.op}
        if len(inputs) == 1:
            entry["input"] = inputs[0]
        elif inputs:
            entry["inputs"] = list(inputs)
        entry.update(op.params())
        nodes.append(entry)
    return {"name": graph.name, "nodes": nodes}


def graph_from_dict(data: Mapping[str, Any], *, registry: OpRegistry | None = None) -> Graph:
    """Build a graph from a chain-file mapping.

    Parameters
    ----------
    data : mapping
        ``{"name": str (optional), "nodes": [node, ...]}`` as described in the module.
    registry : dict[str, type[Op]], optional
        Op name -> op class (default :data:`ir.ops.OP_REGISTRY`).

    Returns
    -------
    Graph
        The graph, not yet verified (call :meth:`Graph.verify`).

    Raises
    ------
    ChainFileError
        Wrong top-level shape, a node that is not a mapping, a missing or malformed
        ``id``, a duplicate id, an unknown ``op`` (listing the valid ones), both
        ``input`` and ``inputs``, or bad parameters (naming the node and field).

    Examples
    --------
    >>> graph_from_dict({"nodes": [{"id": "w", "op": "windw", "axis": "a"}]})
    Traceback (most recent call last):
    ...
    ir.errors.ChainFileError: chain 'chain', node 'w': unknown op 'windw'; valid ops: \
adc_input, add, cfar, classifier, cluster, dft, input, linear, log, magnitude, output, sum, \
threshold, track, window (an op defined in Python is known to readers given its class, \
Graph.from_yaml(..., registry={**ir.OP_REGISTRY, 'windw': ItsClass}); program artifacts and the \
radarsnn command know the built-in ops only; docs/howto-op.md)
    """
    registry = OP_REGISTRY if registry is None else registry
    if not isinstance(data, Mapping):
        raise ChainFileError(
            f"a chain must be a mapping with keys {list(_TOP_KEYS)}; got {type(data).__name__}"
        )
    extra = [k for k in data if k not in _TOP_KEYS]
    if extra:
        raise ChainFileError(f"unknown top-level keys {extra}; allowed: {list(_TOP_KEYS)}")
    name = data.get("name", "chain")
    if not isinstance(name, str) or not name:
        raise ChainFileError(f"chain 'name' must be a non-empty string; got {short_repr(name)}")
    nodes = data.get("nodes")
    if not isinstance(nodes, list):
        raise ChainFileError(
            f"chain {name!r}: 'nodes' must be a list of node mappings; got {type(nodes).__name__}"
        )
    graph = Graph(name)
    first_index: dict[str, int] = {}
    for index, entry in enumerate(nodes):
        id, op_cls, inputs, params = _read_envelope(name, index, entry, registry)
        if id in first_index:
            raise ChainFileError(
                f"chain {name!r}: duplicate node id {id!r} (nodes #{first_index[id]} and "
                f"#{index}); ids must be unique",
                node=id,
            )
        first_index[id] = index
        try:
            op = op_cls.model_validate(params)
        except (ValidationError, IRError) as err:
            # IRModel.__init__ turns ValidationError into IRError (pydantic runs a custom
            # __init__ from model_validate too); describe the original, naming the node.
            cause = err if isinstance(err, ValidationError) else err.__cause__
            reason = describe_validation_error(cause) if cause is not None else str(err)
            raise ChainFileError(
                f"chain {name!r}, node {id!r} ({op_cls.op_name()}): {reason}", node=id
            ) from err
        graph.add(op, inputs=inputs, id=id)
    return graph


def _read_envelope(
    name: str, index: int, entry: object, registry: OpRegistry
) -> tuple[str, type, tuple[str, ...], dict[str, Any]]:
    """Split one node mapping into id, op class, input ids and op parameters."""
    where = f"chain {name!r}, node #{index}"
    if not isinstance(entry, Mapping):
        raise ChainFileError(f"{where}: must be a mapping with 'id' and 'op'; got "
                             f"{short_repr(entry)}")
    id = entry.get("id")
    if not is_name(id):
        raise ChainFileError(
            f"{where}: " + ("missing 'id'" if id is None else f"malformed id {short_repr(id)}")
            + "; ids use letters, digits, '_' or '-' and do not start with a digit"
        )
    where = f"chain {name!r}, node {id!r}"
    odd = [k for k in entry if not isinstance(k, str)]
    if odd:  # op parameters are keyword arguments
        raise ChainFileError(f"{where}: key {short_repr(odd[0])} ({type(odd[0]).__name__}) is "
                             "not a field name; quote it or remove it", node=id)
    op_name = entry.get("op")
    if not isinstance(op_name, str) or op_name not in registry:  # a list/dict is unhashable
        own = (f" (an op defined in Python is known to readers given its class, "
               f"Graph.from_yaml(..., registry={{**ir.OP_REGISTRY, {op_name!r}: ItsClass}}); "
               "program artifacts and the radarsnn command know the built-in ops only; "
               "docs/howto-op.md)" if isinstance(op_name, str) and is_name(op_name) else "")
        raise ChainFileError(
            f"{where}: "
            + ("missing 'op'" if op_name is None else f"unknown op {short_repr(op_name)}")
            + f"; valid ops: {', '.join(sorted(registry))}{own}",
            node=id,
        )
    if "input" in entry and "inputs" in entry:
        raise ChainFileError(f"{where}: give 'input' (one id) or 'inputs' (a list), not both",
                             node=id)
    if "input" in entry:
        inputs = [entry["input"]]
    else:
        inputs = entry.get("inputs", [])
        if not isinstance(inputs, list):
            raise ChainFileError(f"{where}: 'inputs' must be a list of ids; got "
                                 f"{short_repr(inputs)}", node=id)
    bad = [i for i in inputs if not is_name(i)]
    if bad:
        raise ChainFileError(f"{where}: malformed input id {short_repr(bad[0])}", node=id)
    params = {k: v for k, v in entry.items() if k not in _ENVELOPE}
    params["op"] = op_name
    return id, registry[op_name], tuple(inputs), params


# -- YAML ---------------------------------------------------------------------------------


def graph_to_yaml(graph: Graph) -> str:
    """The chain file of ``graph`` as YAML (block nodes, flow-style leaves)."""
    return yaml.safe_dump(
        graph_to_dict(graph), sort_keys=False, default_flow_style=None, width=100
    )


def graph_from_yaml(source: str | Path, *, registry: OpRegistry | None = None) -> Graph:
    """Read a chain from the file at ``source`` (a path, or a one-line ``str``), or from YAML
    text (a multi-line ``str``).

    Raises
    ------
    ChainFileError
        Unreadable file, invalid YAML, duplicate keys, or any error of
        :func:`graph_from_dict` (prefixed with the file name).
    """
    text, label = _read_source(source)
    try:
        data = load_yaml(text, error=ChainFileError)
        return graph_from_dict(_as_mapping(data, source), registry=registry)
    except yaml.YAMLError as err:
        raise ChainFileError(f"{label}invalid YAML: {describe_yaml_error(err)}") from err
    except ChainFileError as err:
        raise ChainFileError(f"{label}{err}", node=err.node) from err


def describe_yaml_error(err: yaml.YAMLError) -> str:
    """A PyYAML error on one line: ``line L, column C: <problem> (<context>)``.

    Examples
    --------
    >>> try:
    ...     yaml.safe_load("a: [1,\\nb: 2}")
    ... except yaml.YAMLError as err:
    ...     print(describe_yaml_error(err))
    line 2, column 5: expected ',' or ']', but got '}' (while parsing a flow sequence)
    """
    mark = getattr(err, "problem_mark", None)
    problem = getattr(err, "problem", None)
    if mark is None or problem is None:
        return " ".join(str(err).split())
    context = getattr(err, "context", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}"
    return f"{where}: {problem}" + (f" ({context})" if context else "")


def load_yaml_mapping(text: str, label: str, fields: str, *,
                      error: type[IRError] | type[Exception] = ChainFileError) -> dict:
    """The mapping a YAML file holds (a profile, a sweep), parsed within the bounds of
    :func:`ir.parsing.load_yaml`; every failure one ``error`` line prefixed by ``label``.

    Examples
    --------
    >>> load_yaml_mapping("a: 1", "f.yaml", "fields")
    {'a': 1}
    >>> load_yaml_mapping("[1, 2]", "f.yaml", "profile fields")
    Traceback (most recent call last):
    ...
    ir.errors.ChainFileError: f.yaml: expected a mapping of profile fields, got list
    >>> try:
    ...     load_yaml_mapping("a: [1,\\nb: 2}", "f.yaml", "fields")
    ... except ChainFileError as err:
    ...     print(str(err)[:41])
    f.yaml: not valid YAML: line 2, column 5:
    """
    try:
        data = load_yaml(text, error=error)
    except yaml.YAMLError as err:
        raise error(f"{label}: not valid YAML: {describe_yaml_error(err)}") from err
    except error as err:
        raise error(f"{label}: {err}") from err
    if not isinstance(data, dict):
        raise error(f"{label}: expected a mapping of {fields}, got {type(data).__name__}")
    return data


# -- JSON ---------------------------------------------------------------------------------


def graph_to_json(graph: Graph) -> str:
    """The chain file of ``graph`` as indented JSON."""
    return json.dumps(graph_to_dict(graph), indent=2, allow_nan=False) + "\n"


def graph_from_json(source: str | Path, *, registry: OpRegistry | None = None) -> Graph:
    """Read a chain from JSON text (a ``str``), or from the file at ``source`` (a path).

    Raises
    ------
    ChainFileError
        Unreadable file, invalid JSON (including NaN/Infinity and duplicate keys),
        or any error of :func:`graph_from_dict` (prefixed with the file name).
    """
    text, label = _read_source(source)
    try:
        data = load_json(text, error=ChainFileError, object_pairs_hook=_unique_pairs,
                         parse_constant=_no_constant)
        return graph_from_dict(_as_mapping(data, source), registry=registry)
    except json.JSONDecodeError as err:
        raise ChainFileError(f"{label}invalid JSON: {err}") from err
    except ChainFileError as err:
        raise ChainFileError(f"{label}{err}", node=err.node) from err


def _unique_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ChainFileError(f"duplicate key {key!r} in a JSON object; remove one")
        out[key] = value
    return out


def _no_constant(name: str) -> Any:
    raise ChainFileError(f"{name} is not a number a chain file may hold; use a finite value")


# -- shared -------------------------------------------------------------------------------


def _read_source(source: str | Path) -> tuple[str, str]:
    """The text and an error-message prefix (the file name for paths).

    A path object is a file; a ``str`` is chain text when it spans several lines
    or starts like a mapping (``{``), and a file name otherwise.
    """
    if isinstance(source, str) and "\n" not in source and not source.lstrip().startswith("{"):
        source = Path(source)
    if isinstance(source, os.PathLike):
        try:
            info = Path(source).stat()
            if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_CHAIN_FILE_BYTES:
                what = ("not a regular file" if not stat.S_ISREG(info.st_mode) else
                        f"{info.st_size} bytes, over the {MAX_CHAIN_FILE_BYTES}-byte limit")
                raise ChainFileError(f"{source}: cannot read the chain file: {what}")
            return Path(source).read_text(encoding="utf-8"), f"{source}: "
        except (OSError, ValueError) as err:  # UnicodeDecodeError; a NUL byte in the path
            raise ChainFileError(f"{source}: cannot read the chain file: {err}") from err
    if isinstance(source, str):
        return source, ""
    raise ChainFileError(
        f"expected chain text (str) or a path (pathlib.Path); got {type(source).__name__}"
    )


def _as_mapping(data: object, source: str | Path) -> object:
    """A chain document is a mapping; say what was found instead."""
    if not isinstance(data, dict):
        raise ChainFileError(f"a chain must be a mapping with 'name' and 'nodes', got "
                             f"{type(data).__name__}")
    return data
