"""Resource limits: a limit's value checked where it is taken, and the memory of values
computed from their types before anything is allocated.

:func:`check_limit` is the one rule for ``max_memory_bytes``, ``max_time_s`` and
``raster_limit_bytes`` everywhere (compile options, :func:`~compiler.compile_guards.check_compile`,
``simulate``, ``run_program``): a positive finite number, or ``None`` for no limit.  A NaN
would switch a guard off (every comparison with NaN is false); a string would fail deep
inside it.

:func:`check_value_sizes` adds up what the values of some nodes take
(:attr:`~ir.types.TensorType.nbytes`) and refuses over a limit, naming the largest node; a
value no array can hold (more than ``sys.maxsize`` bytes) is refused whatever the limit.
:func:`~ir.interpreter.evaluate`, :func:`~compiler.calibration.synthetic_inputs`,
``run_program`` and the compile guard call it.
"""

from __future__ import annotations

import math
import numbers
import sys
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

from ir.errors import IRError, RadarSNNError, SimulationError
from ir.model import short_repr
from ir.types import TensorType

if TYPE_CHECKING:
    from ir.graph import Graph

__all__ = ["MAX_VALUE_BYTES", "check_limit", "check_value_sizes", "human_bytes"]

#: Default limit on the values :func:`ir.interpreter.evaluate` holds (it keeps every node's
#: value): 8 GiB, like the compile and simulation guards.
MAX_VALUE_BYTES = 8 << 30


def check_value_sizes(graph: Graph, types: Mapping[str, TensorType], nodes: Iterable[str], *,
                      max_memory_bytes: int | None, error: type[RadarSNNError] = IRError,
                      doing: str = "evaluating") -> int:
    """Refuse before anything is allocated when the values of ``nodes`` would not fit.

    The sizes come from the inferred types alone (:attr:`TensorType.nbytes`), so a chain
    whose ``n_fft`` is ``2**63`` or whose axis is ``2**62`` long is refused here, naming
    the largest node, instead of failing inside numpy.

    Parameters
    ----------
    graph : Graph
        The chain (for its name and the nodes' ops).
    types : mapping of str to TensorType
        Its inferred types.
    nodes : iterable of str
        The nodes whose values are held together.
    max_memory_bytes : int or None
        The limit (``None``: no limit).
    error : type of RadarSNNError
        Raised over the limit (:class:`~ir.errors.IRError` by default).
    doing : str
        What needs the values, for the message.

    Returns
    -------
    int
        The values' total size in bytes.

    Examples
    --------
    >>> from ir import Graph
    >>> g = Graph.from_dict({"nodes": [{"id": "x", "op": "input", "shape": {"a": 2**40}},
    ...                                {"id": "o", "op": "output", "input": "x"}]})
    >>> check_value_sizes(g, g.infer_types(), ["x"], max_memory_bytes=8 << 30)
    Traceback (most recent call last):
    ...
    ir.errors.IRError: graph 'chain': evaluating needs 8.8e+12 bytes for the values (over \
max_memory_bytes=8589934592); the largest is node 'x' (input), a {'a': 1099511627776} real \
value of 8.8e+12 bytes; shrink its axes (or n_fft) or raise max_memory_bytes
    """
    sizes = {n: types[n].nbytes for n in nodes}
    total = sum(sizes.values())
    node = max(sizes, key=sizes.__getitem__, default=None)
    if node is None:
        return total
    t = types[node]
    if sizes[node] > sys.maxsize:  # whatever the limit: numpy cannot index it
        raise error(f"graph {graph.name!r}: node {node!r} ({graph.op(node).op}) is a "
                    f"{dict(t.axes)} value of {sizes[node]:.2g} bytes, more than any array can "
                    f"hold ({sys.maxsize} bytes); shrink its axes (or n_fft)", node=node)
    if max_memory_bytes is None or total <= max_memory_bytes:
        return total
    raise error(f"graph {graph.name!r}: {doing} needs {total:.2g} bytes for the values (over "
                f"max_memory_bytes={max_memory_bytes}); the largest is node {node!r} "
                f"({graph.op(node).op}), a {dict(t.axes)} {'complex' if t.complex else 'real'} "
                f"value of {sizes[node]:.2g} bytes; shrink its axes (or n_fft) or raise "
                "max_memory_bytes", node=node)


def check_limit(name: str, value: object, unit: str, *, where: str,
                error: type[RadarSNNError] = SimulationError) -> int | float | None:
    """A resource limit's value, refused unless it is a positive finite number or None.

    A NaN limit would switch its guard off (every comparison with NaN is False) and a
    string would fail deep in the guard with a ``TypeError``, so both are refused up front.

    Parameters
    ----------
    name : str
        The option (``max_memory_bytes``, ``max_time_s``, ...).
    value : object
        Its value; ``None`` means no limit.
    unit : str
        ``"bytes"`` (the value becomes an ``int``) or ``"s"`` (a ``float``).
    where : str
        Who takes the option, for the message (``"simulate"``, ``"compile option"``).
    error : type of RadarSNNError
        Raised for a bad value (:class:`~ir.errors.SimulationError` by default).

    Returns
    -------
    int, float or None

    Examples
    --------
    >>> check_limit("max_time_s", 60, "s", where="simulate")
    60.0
    >>> check_limit("max_memory_bytes", float("nan"), "bytes", where="simulate")
    Traceback (most recent call last):
    ...
    ir.errors.SimulationError: simulate: max_memory_bytes=nan must be a positive finite number \
of bytes, or None (no limit)
    """
    if value is None:
        return None
    if (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and math.isfinite(value) and value > 0):
        return int(value) if unit == "bytes" else float(value)
    raise error(f"{where}: {name}={short_repr(value)} must be a positive finite number of "
                f"{unit}, or None (no limit)")


def human_bytes(n: float) -> str:
    """``n`` bytes as a short decimal figure.

    Examples
    --------
    >>> human_bytes(512), human_bytes(3.2e9), human_bytes(8 << 30)
    ('512 B', '3.2 GB', '8.59 GB')

    An integer beyond a float's range (a forged file's count) is given by its bit length:

    >>> human_bytes(10 ** 4000)
    'about 2^13287 B'
    """
    if isinstance(n, int) and n.bit_length() > 1000:
        return f"about 2^{n.bit_length() - 1} B"
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} B"
