"""The reference interpreter: evaluate a graph on numpy arrays with the conventional DSP.

Every op type's reference implementation is its class's ``evaluate``; the
built-in ones are gathered in :data:`~ir.implementations.EVAL_REGISTRY` (op class ->
function, derived from the op registry).  :func:`evaluate` runs a graph node by node
with it, plus any extra implementations it is given (which take precedence over an
op's own), and checks inputs and outputs against the inferred types.

Examples
--------
>>> import numpy as np
>>> from ir.graph import Graph
>>> g = Graph.from_yaml('''
... nodes:
...   - {id: x, op: input, shape: {sample: 4}}
...   - {id: spec, op: dft, input: x, axis: sample}
...   - {id: mag, op: magnitude, input: spec}
...   - {id: out, op: output, input: mag}
... ''')
>>> evaluate(g, {"x": np.array([1.0, 0.0, -1.0, 0.0])})["out"].tolist()
[0.0, 2.0, 0.0, 2.0]
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ir.errors import IRError, RadarSNNError
from ir.frames import frame, n_frames, stack_frames
from ir.graph import Graph
from ir.implementations import EVAL_REGISTRY, EvalRegistry, Implementation
from ir.limits import MAX_VALUE_BYTES, check_limit, check_value_sizes
from ir.model import short_repr
from ir.ops import Op
from ir.ops.registry import reference_implementation
from ir.types import TensorType

__all__ = ["EVAL_REGISTRY", "EvalRegistry", "Implementation", "check_input", "eval_registry",
           "evaluate", "evaluate_node"]

def evaluate(
    graph: Graph,
    inputs: Mapping[str, object],
    *,
    registry: EvalRegistry | None = None,
    max_memory_bytes: int | None = MAX_VALUE_BYTES,
) -> dict[str, np.ndarray]:
    """Evaluate every node of a verified graph on the given input arrays.

    Parameters
    ----------
    graph : Graph
        The chain; it is verified first.
    inputs : mapping of str to array_like
        One array per graph input node (``graph.input_ids()``), shaped as its
        declared axes: complex for complex inputs, real otherwise, boolean for
        ``mask`` inputs, non-negative for ``power`` inputs, all finite.  With one
        extra leading axis of frames on every input (``(F, *declared)``), each frame is
        evaluated as if given alone and every value gets that leading axis
        (:mod:`ir.frames`).
    registry : mapping of op class to implementation, optional
        Implementations that extend or override :data:`EVAL_REGISTRY`.
    max_memory_bytes : int or None
        Limit on the bytes of all the values together, from the types, checked before
        anything is evaluated (default :data:`ir.limits.MAX_VALUE_BYTES`; ``None``: no limit).

    Returns
    -------
    dict[str, ndarray]
        Every node's value keyed by node id, in topological order: float64,
        complex128, or bool for masks; axes in the order of the node's type.

    Raises
    ------
    IRError
        If the graph does not verify, an input is missing or extra, an input array
        has the wrong shape, dtype or non-finite values (naming the input node), an
        op has no implementation, an implementation fails or returns an array that
        does not match the node's type (naming the node), or the graph holds an
        opaque ``classifier`` (no layers) or one whose weights file is missing, or the
        values would take more than ``max_memory_bytes`` (naming the largest node).

    Examples
    --------
    >>> import numpy as np
    >>> from ir.ops import Input, Threshold, Output
    >>> g = Graph()
    >>> g.add(Input(shape={"range": 3}, domain="power"), id="x")
    'x'
    >>> g.add(Threshold(value=1.0, strict=False), inputs="x", id="det")
    'det'
    >>> g.add(Output(), inputs="det", id="out")
    'out'
    >>> evaluate(g, {"x": [0.5, 1.0, 2.0]})["out"].tolist()
    [False, True, True]
    >>> evaluate(g, {"y": [0.5, 1.0, 2.0]})
    Traceback (most recent call last):
    ...
    ir.errors.IRError: graph 'chain': missing input array(s) for ['x']; got arrays for ['y'] \
which are not graph inputs (inputs: ['x'])
    """
    if not isinstance(graph, Graph):
        raise IRError(f"evaluate(graph={short_repr(graph)}): takes an ir.Graph, not "
                      f"{type(graph).__name__}; read a chain file with Graph.from_yaml(path)")
    if not isinstance(inputs, Mapping):
        raise IRError(f"graph {graph.name!r}: inputs must be a mapping of input node id to "
                      f"array, not {type(inputs).__name__}")
    impls = eval_registry(registry)
    graph.verify()
    types = graph.infer_types()
    _check_input_names(graph, inputs)
    count = n_frames(types, inputs, f"graph {graph.name!r}")
    if count is not None:  # the stack holds every frame's values: each frame gets its share
        limit = check_limit("max_memory_bytes", max_memory_bytes, "bytes",
                            where=f"graph {graph.name!r}", error=IRError)
        share = None if limit is None else max(1, int(limit) // count)
        check_value_sizes(graph, types, types, max_memory_bytes=share)
        return stack_frames([evaluate(graph, frame(inputs, i), registry=registry,
                                      max_memory_bytes=share) for i in range(count)])
    check_value_sizes(graph, types, types, max_memory_bytes=max_memory_bytes)
    values: dict[str, np.ndarray] = {}
    for node_id, out_type in types.items():
        op = graph.op(node_id)
        if op.arity == 0:
            values[node_id] = check_input(node_id, out_type, inputs[node_id])
            continue
        in_ids = graph.inputs_of(node_id)
        values[node_id] = evaluate_node(node_id, op, [values[i] for i in in_ids],
                                        [types[i] for i in in_ids], out_type, impls)
    return values


def eval_registry(extra: EvalRegistry | None = None) -> dict[type[Op], Implementation]:
    """The reference implementations: :data:`EVAL_REGISTRY` with ``extra`` added (a new dict).

    Parameters
    ----------
    extra : mapping of op class to implementation, optional
        Implementations of new ops, or replacements of built-in ones.

    Returns
    -------
    dict
        Op class -> implementation; :data:`EVAL_REGISTRY` itself is never changed.

    Raises
    ------
    IRError
        If ``extra`` is not a mapping, a key is not an :class:`~ir.ops.Op` subclass or a
        value is not callable (naming the entry).

    Examples
    --------
    >>> from ir.ops import Magnitude
    >>> impls = eval_registry({Magnitude: lambda node_id, op, args, types: abs(args[0])})
    >>> impls[Magnitude] is EVAL_REGISTRY[Magnitude], len(impls) == len(EVAL_REGISTRY)
    (False, True)
    >>> eval_registry({"magnitude": abs})
    Traceback (most recent call last):
    ...
    ir.errors.IRError: evaluators: key 'magnitude' is not an op class; map op classes to \
functions, e.g. {Scale: evaluate_scale}
    """
    if extra is None:
        return dict(EVAL_REGISTRY)
    if not isinstance(extra, Mapping):
        raise IRError(f"evaluators must be a mapping of op class to function; got "
                      f"{type(extra).__name__}")
    for key, impl in extra.items():
        if not (isinstance(key, type) and issubclass(key, Op)):
            raise IRError(f"evaluators: key {key!r} is not an op class; map op classes to "
                          "functions, e.g. {Scale: evaluate_scale}")
        if not callable(impl):
            raise IRError(f"evaluators: the implementation of {key.__name__} is a "
                          f"{type(impl).__name__}, not a function impl(node_id, op, args, types)")
    return {**EVAL_REGISTRY, **extra}


def evaluate_node(node_id: str, op: Op, args: list[np.ndarray], types: list[TensorType],
                  out_type: TensorType, registry: EvalRegistry) -> np.ndarray:
    """One node's value: its op's implementation applied to its input arrays, checked.

    Parameters
    ----------
    node_id : str
        The node (named in errors).
    op : Op
        Its op.
    args : list of ndarray
        Its input values, in input order.
    types : list of TensorType
        Their types.
    out_type : TensorType
        The node's inferred type; the result must have its shape and kind.
    registry : mapping of op class to implementation
        Where the op's implementation is looked up first (e.g. :func:`eval_registry`);
        an op class it lacks is evaluated with its own ``evaluate``, if it has one.

    Returns
    -------
    ndarray
        float64, complex128, or bool for masks.

    Raises
    ------
    IRError
        No implementation for the op's class (in ``registry`` or its own
        ``evaluate``), an implementation that fails with a
        project error, or a result of the wrong shape or kind (naming the node).

    Examples
    --------
    >>> from ir.ops import Sum
    >>> t = TensorType(axes={"rx": 2, "range": 3})
    >>> evaluate_node("s", Sum(axis="rx"), [np.ones((2, 3))], [t],
    ...               TensorType(axes={"range": 3}), EVAL_REGISTRY).tolist()
    [2.0, 2.0, 2.0]
    """
    impl = registry.get(type(op)) or reference_implementation(type(op))
    if impl is None:
        name = type(op).__name__
        raise IRError(
            f"node {node_id!r} ({op.op}): no implementation for {name}; pass "
            f"{{{name}: function}} as evaluate(..., registry=) or "
            f"compile_graph(..., evaluators=), or define {name}.evaluate (docs/howto-op.md)",
            node=node_id,
        )
    try:
        out = impl(node_id, op, args, types)
    except IRError:
        raise
    except RadarSNNError as err:
        raise IRError(f"node {node_id!r} ({op.op}): {err}", node=node_id) from err
    return _check_output(node_id, op, out_type, out)


def _check_input_names(graph: Graph, inputs: Mapping[str, object]) -> None:
    expected = graph.input_ids()
    missing = [i for i in expected if i not in inputs]
    extra = [k for k in inputs if k not in expected]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"missing input array(s) for {missing}")
        if extra:
            parts.append(f"got arrays for {extra} which are not graph inputs")
        raise IRError(
            f"graph {graph.name!r}: {'; '.join(parts)} (inputs: {expected})",
            node=missing[0] if missing else str(extra[0]),
        )


def check_input(node_id: str, t: TensorType, value: object) -> np.ndarray:
    """Validate one input array against its declared type and return a fresh copy.

    Parameters
    ----------
    node_id : str
        The input node (named in errors).
    t : TensorType
        Its declared type.
    value : array_like
        The supplied values.

    Returns
    -------
    ndarray
        float64, complex128 (complex types) or bool (``mask``), shape ``t.shape``.

    Raises
    ------
    IRError
        Wrong shape, complex given for a real input or vice versa, a non-boolean
        mask, a non-numeric array, non-finite values, or negative powers.

    Examples
    --------
    >>> t = TensorType(axes={"chirp": 2, "sample": 3})
    >>> check_input("adc", t, np.zeros((3, 2)))
    Traceback (most recent call last):
    ...
    ir.errors.IRError: input 'adc': array shape (3, 2) does not match the declared axes \
{'chirp': 2, 'sample': 3}, shape (2, 3)
    """
    where = f"input {node_id!r}"
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as err:  # ragged nested lists, objects numpy cannot hold
        raise IRError(f"{where}: not an array ({err})", node=node_id) from None
    if arr.shape != t.shape:
        raise IRError(
            f"{where}: array shape {arr.shape} does not match the declared axes "
            f"{dict(t.axes)}, shape {t.shape}",
            node=node_id,
        )
    if t.domain == "mask":
        if arr.dtype != np.bool_:
            raise IRError(f"{where}: a mask input needs a bool array; got {arr.dtype}",
                          node=node_id)
        return arr.astype(np.bool_, copy=True)
    if arr.dtype.kind not in "iufc":
        raise IRError(f"{where}: needs a numeric array; got dtype {arr.dtype}", node=node_id)
    if np.iscomplexobj(arr) != t.complex:
        raise IRError(
            f"{where}: declared {'complex' if t.complex else 'real'} but the array is "
            f"{arr.dtype}; "
            + ("pass complex I/Q samples (e.g. x.astype(complex))" if t.complex
               else "declare complex: true or pass a real array"),
            node=node_id,
        )
    arr = arr.astype(np.complex128 if t.complex else np.float64, copy=True)
    bad = ~np.isfinite(arr)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise IRError(
            f"{where}: {int(bad.sum())} non-finite value(s) (NaN/Inf) of {arr.size}, first at "
            f"index {first}; clean the data (e.g. np.nan_to_num) first",
            node=node_id,
        )
    if t.domain == "power" and (arr < 0).any():
        raise IRError(
            f"{where}: a power input must be >= 0; minimum is {arr.min():.6g}", node=node_id
        )
    return arr




def _check_output(node_id: str, op: Op, t: TensorType, out: object) -> np.ndarray:
    """Cast an implementation's result to the node's dtype, refusing the wrong shape."""
    arr = np.asarray(out)
    dtype = np.bool_ if t.domain == "mask" else np.complex128 if t.complex else np.float64
    if arr.shape != t.shape or (np.iscomplexobj(arr) and not t.complex):
        raise IRError(
            f"node {node_id!r} ({op.op}): the implementation returned a {arr.dtype} array of "
            f"shape {arr.shape}, but the node's type is {t!r}; fix the implementation",
            node=node_id,
        )
    return arr.astype(dtype, copy=False)
