"""``Graph``: a radar DSP chain as a directed acyclic graph of ops keyed by string ids.

Each node holds one op (a frozen record from :mod:`ir.ops`) and the ordered ids
of its inputs; an edge ``a -> b`` means node ``b`` reads the value of node ``a``.
Nodes may name inputs that are added later (or never): :meth:`Graph.verify`
reports unknown ids, self-loops, cycles and unused values before it checks
every node's types in topological order.

Examples
--------
>>> from ir.ops import AdcInput, DFT, Magnitude, Output
>>> g = Graph("toy")
>>> g.add(AdcInput(shape={"sample": 8}), id="adc")
'adc'
>>> g.add(DFT(axis="sample", out_axis="range", keep="positive"), inputs=["adc"])
'dft_0'
>>> g.add(Magnitude(), inputs=["dft_0"], id="mag")
'mag'
>>> g.add(Output(), inputs=["mag"], id="out")
'out'
>>> g.verify()
>>> g.infer_types()["mag"]
TensorType(axes={'range': 4}, complex=False, domain='amplitude')
>>> g.input_ids(), g.output_ids()
(['adc'], ['out'])
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import networkx as nx

from ir.errors import IRError
from ir.model import is_name
from ir.ops import Op, OpRegistry
from ir.types import TensorType

__all__ = ["Graph"]


class Graph:
    """A radar DSP chain: ops as nodes of a ``networkx.DiGraph`` keyed by string ids.

    Parameters
    ----------
    name : str, default "chain"
        The chain's name (free text, non-empty).

    Raises
    ------
    IRError
        If ``name`` is not a non-empty string.
    """

    def __init__(self, name: str = "chain") -> None:
        if not isinstance(name, str) or not name:
            raise IRError(f"graph name must be a non-empty string; got {name!r}")
        self.name = name
        self._g = nx.DiGraph()
        self._index: dict[str, int] = {}
        self._waiting: dict[str, set[str]] = {}  # missing input id -> nodes that read it

    # -- building ----------------------------------------------------------------------

    def add(self, op: Op, inputs: Sequence[str] | str = (), id: str | None = None) -> str:
        """Add a node and return its id.

        Parameters
        ----------
        op : Op
            The op the node applies.
        inputs : sequence of str, or str
            Ids of the nodes it reads, in order (a single id may be given as a string).
            They may be added later; :meth:`verify` reports ids that never appear.
        id : str, optional
            The node id (letters, digits, ``_``, ``-``; not starting with a digit).
            Default ``<op>_<n>`` with the smallest free ``n``.

        Returns
        -------
        str
            The node id.

        Raises
        ------
        IRError
            If ``op`` is not an op, an id is malformed, or ``id`` is already taken.

        Examples
        --------
        >>> from ir.ops import Input
        >>> g = Graph()
        >>> g.add(Input(shape={"range": 4}))
        'input_0'
        >>> g.add(Input(shape={"range": 4}), id="input_0")
        Traceback (most recent call last):
        ...
        ir.errors.IRError: graph 'chain': duplicate node id 'input_0'; ids must be unique
        """
        if not isinstance(op, Op):
            raise IRError(f"graph {self.name!r}: expected an op, got {type(op).__name__}")
        inputs = (inputs,) if isinstance(inputs, str) else tuple(inputs)
        if id is None:
            id = self._free_id(op.op)
        for name, what in [(id, "node id"), *((i, "input id") for i in inputs)]:
            if not is_name(name):
                raise IRError(
                    f"graph {self.name!r}: malformed {what} {name!r}; use letters, digits, "
                    "'_' or '-', not starting with a digit",
                    node=id if isinstance(id, str) else None,
                )
        if id in self._index:
            raise IRError(
                f"graph {self.name!r}: duplicate node id {id!r}; ids must be unique", node=id
            )
        self._index[id] = len(self._index)
        self._g.add_node(id, op=op, inputs=inputs)
        for src in inputs:
            if src in self._index:
                self._g.add_edge(src, id)
            else:
                self._waiting.setdefault(src, set()).add(id)
        for dst in self._waiting.pop(id, ()):
            self._g.add_edge(id, dst)
        return id

    def _free_id(self, op_name: str) -> str:
        n = 0
        while f"{op_name}_{n}" in self._index:
            n += 1
        return f"{op_name}_{n}"

    # -- reading -----------------------------------------------------------------------

    def __len__(self) -> int:
        return len(self._index)

    def __iter__(self) -> Iterator[str]:
        """Node ids in insertion order."""
        return iter(self._index)

    def __contains__(self, id: object) -> bool:
        return id in self._index

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Graph):
            return NotImplemented
        return self._key() == other._key()

    __hash__ = None  # mutable

    def _key(self) -> tuple:
        return (self.name, [(i, self.op(i), self.inputs_of(i)) for i in self])

    def __repr__(self) -> str:
        return f"Graph({self.name!r}, {len(self)} nodes)"

    def _node(self, id: str) -> dict[str, Any]:
        if id not in self._index:
            raise IRError(
                f"graph {self.name!r}: no node {id!r}; nodes: {list(self._index)}", node=id
            )
        return self._g.nodes[id]

    def op(self, id: str) -> Op:
        """The op of node ``id`` (IRError if there is no such node)."""
        return self._node(id)["op"]

    def inputs_of(self, id: str) -> tuple[str, ...]:
        """The ids node ``id`` reads, in order."""
        return self._node(id)["inputs"]

    def consumers_of(self, id: str) -> list[str]:
        """The ids of the nodes that read node ``id``, in insertion order."""
        self._node(id)
        return sorted(self._g.successors(id), key=self._index.__getitem__)

    def input_ids(self) -> list[str]:
        """Ids of the graph inputs (ops that take no inputs), in insertion order."""
        return [i for i in self if self.op(i).arity == 0]

    def output_ids(self) -> list[str]:
        """Ids of the ``output`` nodes, in insertion order."""
        return [i for i in self if self.op(i).is_output]

    def to_networkx(self) -> nx.DiGraph:
        """A copy of the underlying ``networkx.DiGraph`` (node attributes ``op``, ``inputs``)."""
        return self._g.copy()

    # -- checking ----------------------------------------------------------------------

    def _check_structure(self) -> None:
        """Self-loops, cycles and unknown input ids, each naming the node(s)."""
        for id in self:
            if id in self.inputs_of(id):
                raise IRError(
                    f"node {id!r} ({self.op(id).op}): reads its own value (self-loop); "
                    "a chain must be acyclic",
                    node=id,
                )
        try:
            cycle = nx.find_cycle(self._g)
        except nx.NetworkXNoCycle:
            cycle = []
        if cycle:
            nodes = [u for u, _ in cycle]
            path = " -> ".join([*nodes, nodes[0]])
            raise IRError(
                f"graph {self.name!r}: cycle through nodes {nodes} ({path}); "
                "a chain must be acyclic",
                node=nodes[0],
            )
        for missing, readers in self._waiting.items():
            reader = min(readers, key=self._index.__getitem__)
            raise IRError(
                f"node {reader!r} ({self.op(reader).op}): unknown input id {missing!r}; "
                f"nodes: {list(self._index)}",
                node=reader,
            )

    def topological_order(self) -> list[str]:
        """Node ids so that every node comes after its inputs (ties: insertion order).

        Raises
        ------
        IRError
            On a self-loop, a cycle (naming the nodes on it) or an unknown input id.
        """
        self._check_structure()
        return list(nx.lexicographical_topological_sort(self._g, key=self._index.__getitem__))

    def infer_types(self) -> dict[str, TensorType]:
        """The type of every node's value, keyed by node id in topological order.

        Raises
        ------
        IRError
            The structural errors of :meth:`topological_order`, or the first node
            (in topological order) whose op rejects its inputs.
        """
        types: dict[str, TensorType] = {}
        for id in self.topological_order():
            op = self.op(id)
            args = [types[i] for i in self.inputs_of(id)]
            try:
                types[id] = op.infer(id, args)
            except IRError as err:
                if err.node is not None:
                    raise
                raise IRError(f"node {id!r} ({op.op}): {err}", node=id) from err
        return types

    def verify(self) -> None:
        """Check the whole graph; return nothing if it is valid.

        Checks, in order: the graph is not empty; no self-loops; no cycles; no
        unknown input ids; no node with fewer inputs than its op takes (so a node
        that lacks ``input`` is named, not the node it should have read); every value
        is used (only ``output`` nodes may be unread); every node's op accepts its
        input types.

        Raises
        ------
        IRError
            At the first problem found, naming the node (or the nodes on a cycle).
        """
        if not self._index:
            raise IRError(f"graph {self.name!r} has no nodes; add an input node")
        self._check_structure()
        for id in self:
            op, given = self.op(id), len(self.inputs_of(id))
            if given < op.arity:
                plural = "input" if op.arity == 1 else "inputs"
                give = "'input: <node id>'" if op.arity == 1 else "'inputs: [<node id>, ...]'"
                raise op.fail(id, f"takes {op.arity} {plural}, got {given}; give {give} "
                                  f"(nodes: {list(self._index)})")
        for id in self:
            if not self.op(id).is_output and self._g.out_degree(id) == 0:
                raise IRError(
                    f"node {id!r} ({self.op(id).op}): dangling, its value is not read by any "
                    f"node; add an output node reading it ({{id: out, op: output, input: {id}}}) "
                    "or remove it",
                    node=id,
                )
        self.infer_types()

    # -- chain files (see ir.serialize) -----------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The chain-file mapping ``{"name": ..., "nodes": [...]}`` (see :mod:`ir.serialize`)."""
        from ir.serialize import graph_to_dict  # serialize builds graphs: a cycle

        return graph_to_dict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, registry: OpRegistry | None = None) -> Graph:
        """Build a graph from a chain-file mapping (see :mod:`ir.serialize`)."""
        from ir.serialize import graph_from_dict  # serialize builds graphs: a cycle

        return graph_from_dict(data, registry=registry)

    def to_yaml(self) -> str:
        """The chain file as YAML text."""
        from ir.serialize import graph_to_yaml  # serialize builds graphs: a cycle

        return graph_to_yaml(self)

    @classmethod
    def from_yaml(cls, source: str | Path, *, registry: OpRegistry | None = None) -> Graph:
        """Read a chain from YAML text, or from a file if ``source`` is a ``Path``."""
        from ir.serialize import graph_from_yaml  # serialize builds graphs: a cycle

        return graph_from_yaml(source, registry=registry)

    def to_json(self) -> str:
        """The chain file as JSON text."""
        from ir.serialize import graph_to_json  # serialize builds graphs: a cycle

        return graph_to_json(self)

    @classmethod
    def from_json(cls, source: str | Path, *, registry: OpRegistry | None = None) -> Graph:
        """Read a chain from JSON text, or from a file if ``source`` is a ``Path``."""
        from ir.serialize import graph_from_json  # serialize builds graphs: a cycle

        return graph_from_json(source, registry=registry)
