"""JSON Schema of chain files, generated from the op registry.

Each op class gets a node model (the op's fields plus ``id``, ``input`` and
``inputs``); the ``nodes`` list is a pydantic discriminated union on ``op``. The
same registry drives :func:`ir.serialize.graph_from_dict`, so the schema and the
reader cannot disagree about which ops exist or what they take.

Examples
--------
>>> schema = chain_schema()
>>> schema["required"], sorted(schema["properties"])
(['nodes'], ['name', 'nodes'])
>>> sorted(schema["properties"]["nodes"]["items"]["discriminator"]["mapping"])[:3]
['adc_input', 'add', 'cfar']
"""

from __future__ import annotations

import functools
import operator
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, create_model

from ir.model import Name
from ir.ops import OP_REGISTRY, Op, OpRegistry

__all__ = ["chain_file_model", "chain_schema"]

JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def _node_model(op_cls: type[Op]) -> type[BaseModel]:
    """The chain-file node of one op: its parameters plus the envelope keys."""
    return create_model(
        f"{op_cls.__name__}Node",
        __base__=op_cls,
        __doc__=(op_cls.__doc__ or "").split("\n", 1)[0],
        op=(op_cls.model_fields["op"].annotation, Field(description="The op name.")),
        id=(Name, Field(description="Node id, unique in the chain.")),
        input=(Name | None, Field(default=None, description="The one input node id.")),
        inputs=(list[Name] | None, Field(default=None, description="Input node ids, in order.")),
    )


def chain_file_model(registry: OpRegistry | None = None) -> type[BaseModel]:
    """A pydantic model of a whole chain file for the ops in ``registry``.

    Parameters
    ----------
    registry : dict[str, type[Op]], optional
        Op name -> class (default :data:`ir.ops.OP_REGISTRY`).

    Returns
    -------
    type[pydantic.BaseModel]
        ``ChainFile`` with ``name: str = "chain"`` and ``nodes: list[<node union>]``.

    Examples
    --------
    >>> model = chain_file_model()
    >>> model.model_validate({"nodes": [{"id": "x", "op": "input", "shape": {"a": 2}}]}).name
    'chain'
    """
    registry = OP_REGISTRY if registry is None else registry
    return _chain_file_model(tuple(registry.values()))


@functools.lru_cache(maxsize=16)
def _chain_file_model(op_classes: tuple[type[Op], ...]) -> type[BaseModel]:
    nodes = [_node_model(cls) for cls in op_classes]
    union: Any = functools.reduce(operator.or_, nodes)
    if len(nodes) > 1:
        union = Annotated[union, Field(discriminator="op")]
    return create_model(
        "ChainFile",
        __config__=ConfigDict(extra="forbid", title="radarsnn chain file"),
        __doc__="A radar DSP chain: a name and its nodes (see docs/ir.md).",
        name=(str, Field(default="chain", min_length=1, description="The chain's name.")),
        nodes=(list[union], Field(description="The nodes; each has an id and an op.")),
    )


def chain_schema(registry: OpRegistry | None = None) -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of chain files for the ops in ``registry``.

    Parameters
    ----------
    registry : dict[str, type[Op]], optional
        Op name -> class (default :data:`ir.ops.OP_REGISTRY`).

    Returns
    -------
    dict
        The schema; ``nodes`` items are a ``oneOf`` with a discriminator on ``op``.

    Notes
    -----
    The schema checks each node on its own; cross-node rules (known input ids,
    acyclic, axis names and sizes) are :meth:`ir.graph.Graph.verify`'s job.
    """
    schema = chain_file_model(registry).model_json_schema()
    return {"$schema": JSON_SCHEMA_DIALECT, **schema}
