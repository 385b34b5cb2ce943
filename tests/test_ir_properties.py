"""Property tests of the IR: random valid chains verify, round-trip and evaluate to their
types; random corruptions of them raise IRError naming the corrupted node, never anything else.
"""

from __future__ import annotations

import copy
import math

import networkx as nx
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ir import (
    CFAR,
    DFT,
    AdcInput,
    Classifier,
    Graph,
    Input,
    IRError,
    Linear,
    Log,
    Magnitude,
    Output,
    Sum,
    TensorType,
    Threshold,
    Window,
    chain_file_model,
    evaluate,
)

# Generated names are at most 7 characters, so the corruptions' longer names never collide.
_LETTERS = "abcdefghijklmnopqrstuvwxyz"
NAMES = st.builds(
    "".join, st.tuples(st.sampled_from(_LETTERS), st.text(_LETTERS + "0123456789_", max_size=6))
)
MISSING_AXIS = "zz_missing_axis"
GHOST_ID = "ghost_node_x"


def _fresh(draw: st.DrawFn, taken: object) -> str | None:
    """A generated name not in ``taken``, or None (then the default applies)."""
    name = draw(NAMES)
    return None if name in taken else name


# -- one strategy per op: given an input type, the ops that fit it ------------------------


@st.composite
def _shapes(draw: st.DrawFn) -> dict[str, int]:
    names = draw(st.lists(NAMES, min_size=1, max_size=3, unique=True))
    return {n: draw(st.integers(1, 9)) for n in names}


@st.composite
def _source(draw: st.DrawFn) -> AdcInput | Input:
    shape = draw(_shapes())
    if draw(st.booleans()):
        return AdcInput(shape=shape, complex=draw(st.booleans()))
    domain = draw(st.sampled_from(["amplitude", "power", "db", "mask"]))
    is_complex = domain == "amplitude" and draw(st.booleans())
    return Input(shape=shape, complex=is_complex, domain=domain)


def _out_axis(draw: st.DrawFn, t: TensorType, axis: str) -> str | None:
    return draw(st.sampled_from([None, axis, _fresh(draw, t.axes)]))


@st.composite
def _dft(draw: st.DrawFn, t: TensorType) -> DFT:
    axis = draw(st.sampled_from(t.names))
    size = t.axes[axis]
    n_fft = draw(st.one_of(st.none(), st.integers(size, size + 4)))
    keep = draw(st.sampled_from(["all", "positive"] if (n_fft or size) >= 2 else ["all"]))
    return DFT(axis=axis, out_axis=_out_axis(draw, t, axis), n_fft=n_fft, keep=keep,
               shift=draw(st.booleans()))


_ENTRIES = st.floats(-10, 10, allow_nan=False)


@st.composite
def _linear(draw: st.DrawFn, t: TensorType) -> Linear:
    axis = draw(st.sampled_from(t.names))
    shape = (draw(st.integers(1, 4)), t.axes[axis])
    rows = st.lists(st.lists(_ENTRIES, min_size=shape[1], max_size=shape[1]),
                    min_size=shape[0], max_size=shape[0])
    imag = draw(st.one_of(st.none(), rows))
    return Linear(axis=axis, out_axis=_out_axis(draw, t, axis), matrix=draw(rows),
                  matrix_imag=imag)


def _one_or_list(values: list) -> object:
    return values[0] if len(set(values)) == 1 and len(values) > 0 else values


@st.composite
def _cfar(draw: st.DrawFn, t: TensorType) -> CFAR:
    usable = [a for a in t.names if t.axes[a] >= 3]
    axes = draw(st.permutations(usable).flatmap(
        lambda p: st.integers(1, len(p)).map(lambda n: p[:n])))
    guard, train = [], []
    for i, axis in enumerate(axes):
        half = (t.axes[axis] - 1) // 2  # window 2(g+t)+1 <= size  <=>  g+t <= half
        tr = draw(st.integers(1 if i == 0 else 0, half))
        train.append(tr)
        guard.append(draw(st.integers(0, half - tr)))
    edge = draw(st.lists(st.sampled_from(["wrap", "clip"]), min_size=len(axes),
                         max_size=len(axes)))
    n_train = math.prod(2 * (g + r) + 1 for g, r in zip(guard, train, strict=True)) - math.prod(
        2 * g + 1 for g in guard)
    kind = draw(st.sampled_from(["ca", "os"]))
    use_pfa = t.domain == "power" and draw(st.booleans())
    default_axes = tuple(axes) == t.names and draw(st.booleans())
    return CFAR(
        kind=kind,
        axes=None if default_axes else axes,
        guard=draw(st.sampled_from([guard, _one_or_list(guard)])),
        train=draw(st.sampled_from([train, _one_or_list(train)])),
        alpha=None if use_pfa else draw(st.floats(0.01, 100)),
        pfa=draw(st.floats(1e-8, 0.5)) if use_pfa else None,
        k=draw(st.integers(1, n_train)) if kind == "os" else None,
        edge=draw(st.sampled_from([edge, _one_or_list(edge)])),
    )


_KINDS = {
    "window": ["hann", "hamming", "blackman", "rect"],
    "magnitude": ["l2", "l1", "square"],
}


def _op_names_for(t: TensorType, *, with_classifier: bool) -> list[str]:
    """Names of the ops that accept an input of type ``t`` (the IR's documented rules)."""
    real, dom = not t.complex, t.domain
    fits = {
        "window": dom == "amplitude",
        "dft": dom == "amplitude",
        "linear": dom == "amplitude",
        "sum": dom in ("amplitude", "power") and t.ndim >= 2,
        "magnitude": dom == "amplitude",
        "log": real and dom in ("amplitude", "power"),
        "cfar": real and dom != "mask" and any(n >= 3 for n in t.shape),
        "threshold": real and dom != "mask",
        "classifier": with_classifier and real and dom != "mask" and t.ndim >= 2,
    }
    return [name for name, ok in fits.items() if ok]


def _op_strategy(name: str, t: TensorType) -> st.SearchStrategy:
    axis = st.sampled_from(t.names)
    makers = {
        "window": lambda: st.builds(Window, axis=axis, kind=st.sampled_from(_KINDS["window"])),
        "dft": lambda: _dft(t),
        "linear": lambda: _linear(t),
        "sum": lambda: st.builds(Sum, axis=axis),
        "magnitude": lambda: st.builds(Magnitude, kind=st.sampled_from(_KINDS["magnitude"])),
        "log": lambda: st.builds(Log, floor_db=st.floats(-400, 0)),
        "cfar": lambda: _cfar(t),
        "threshold": lambda: st.builds(
            Threshold, value=st.floats(allow_nan=False, allow_infinity=False),
            strict=st.booleans()),
        "classifier": lambda: st.builds(
            Classifier, num_classes=st.integers(2, 5), weights=st.just("w.npz")),
    }
    return makers[name]()


@st.composite
def chains(draw: st.DrawFn, *, max_ops: int = 6, with_classifier: bool = True) -> Graph:
    """A random valid chain: 1-2 inputs, up to ``max_ops`` ops that fit, an output per sink."""
    graph = Graph(draw(st.text(st.characters(min_codepoint=32, max_codepoint=0x24F),
                               min_size=1, max_size=10)))
    types: dict[str, TensorType] = {}

    def add(op: object, inputs: list[str]) -> str:
        node_id = graph.add(op, inputs, id=_fresh(draw, graph) if draw(st.booleans()) else None)
        types[node_id] = op.infer(node_id, [types[i] for i in inputs])
        return node_id

    for _ in range(draw(st.integers(1, 2))):
        add(draw(_source()), [])
    for _ in range(draw(st.integers(0, max_ops))):
        src = draw(st.sampled_from(list(types)))
        names = _op_names_for(types[src], with_classifier=with_classifier)
        if names:
            add(draw(_op_strategy(draw(st.sampled_from(names)), types[src])), [src])
    for node_id in list(graph):
        if not graph.consumers_of(node_id):
            add(Output(), [node_id])
    return graph


# -- valid chains ---------------------------------------------------------------------------


@given(chains())
def test_random_valid_chains_verify_and_round_trip(graph: Graph) -> None:
    graph.verify()
    text = graph.to_yaml()
    assert Graph.from_yaml(text) == graph
    assert Graph.from_yaml(text).to_yaml() == text
    assert Graph.from_json(graph.to_json()) == graph
    assert Graph.from_dict(graph.to_dict()) == graph
    assert Graph.from_dict(graph.to_dict()).to_dict() == graph.to_dict()
    assert chain_file_model().model_validate(graph.to_dict()).name == graph.name


def _random_inputs(graph: Graph, rng: np.random.Generator) -> dict[str, np.ndarray]:
    types = graph.infer_types()
    arrays = {}
    for node_id in graph.input_ids():
        t = types[node_id]
        x = rng.standard_normal(t.shape)
        if t.complex:
            x = x + 1j * rng.standard_normal(t.shape)
        arrays[node_id] = {"mask": x > 0, "power": np.abs(x)}.get(t.domain, x)
    return arrays


@given(chains(max_ops=5, with_classifier=False), st.integers(0, 2**32 - 1))
def test_evaluate_matches_inferred_types(graph: Graph, seed: int) -> None:
    values = evaluate(graph, _random_inputs(graph, np.random.default_rng(seed)))
    types = graph.infer_types()
    assert list(values) == list(types)
    for node_id, t in types.items():
        value = values[node_id]
        assert value.shape == t.shape
        expected = np.bool_ if t.domain == "mask" else np.complex128 if t.complex else np.float64
        assert value.dtype == expected
        if t.domain != "mask":
            assert np.isfinite(value).all()
        if t.domain == "power":
            assert (value >= 0).all()
    for out in graph.output_ids():
        np.testing.assert_array_equal(values[out], values[graph.inputs_of(out)[0]])


@given(chains(max_ops=3), st.sampled_from(["yaml", "json"]))
def test_cfar_geometry_matches_radar_n_training(graph: Graph, fmt: str) -> None:
    from radar.cfar_window import n_training

    types = graph.infer_types()
    for node_id in graph:
        op = graph.op(node_id)
        if op.op == "cfar":
            (src,) = graph.inputs_of(node_id)
            window = op.window(node_id, types[src])
            assert window.n_train == n_training(list(window.guard), list(window.train))


# -- corruptions ----------------------------------------------------------------------------

_BAD_PARAMS = {
    "adc_input": [{"shape": {"a": 0}}, {"shape": {"1bad": 3}}, {"complex": "maybe"}],
    "input": [{"shape": {}}, {"domain": "volts"}, {"complex": True, "domain": "power"}],
    "output": [{"gain": 2}],
    "window": [{"kind": "triangle"}, {"axis": 3}],
    "dft": [{"n_fft": 0}, {"keep": "half"}, {"shift": "sometimes"}],
    "linear": [{"matrix": [[1.0], [1.0, 2.0]]}, {"matrix": []}, {"matrix": [[float("nan")]]}],
    "sum": [{"axis": None}],
    "magnitude": [{"kind": "l3"}],
    "log": [{"floor_db": "low"}, {"floor_db": float("-inf")}],
    "cfar": [{"alpha": -1.0, "pfa": None}, {"alpha": None, "pfa": 1.5}, {"k": 0},
             {"guard": -1}, {"edge": "mirror"}, {"kind": "go"}, {"alpha": 1.0, "pfa": 0.1}],
    "threshold": [{"value": float("nan")}, {"strict": [1]}],
    "classifier": [{"num_classes": 1}, {"weights": ""}],
}


def _node(data: dict, node_id: str) -> dict:
    return next(n for n in data["nodes"] if n["id"] == node_id)


def _corrupt(graph: Graph, kind: str, data: st.DataObject) -> tuple[dict, str]:
    """A corrupted copy of ``graph``'s chain dict and the id the error must name."""
    d = copy.deepcopy(graph.to_dict())
    d["name"] = "corrupted"
    ids = list(graph)
    readers = [i for i in ids if graph.inputs_of(i)]
    if kind == "cycle":
        target = data.draw(st.sampled_from(readers))
        below = [target, *nx.descendants(graph.to_networkx(), target)]
        _node(d, target)["input"] = data.draw(st.sampled_from(sorted(below)))
        return d, target
    if kind == "bad_axis":
        with_axis = [i for i in ids if graph.op(i).op in ("window", "dft", "linear", "sum", "cfar")]
        if not with_axis:
            target = data.draw(st.sampled_from(graph.input_ids()))
            node = _node(d, target)
            node["shape"] = {"2" + k: v for k, v in node["shape"].items()}
            return d, target
        target = data.draw(st.sampled_from(with_axis))
        key = "axes" if graph.op(target).op == "cfar" else "axis"
        _node(d, target)[key] = [MISSING_AXIS] if key == "axes" else MISSING_AXIS
        return d, target
    if kind == "bad_param":
        target = data.draw(st.sampled_from(ids))
        _node(d, target).update(data.draw(st.sampled_from(_BAD_PARAMS[graph.op(target).op])))
        return d, target
    if kind == "unknown_input":
        target = data.draw(st.sampled_from(readers))
        _node(d, target)["input"] = GHOST_ID
        return d, target
    if kind == "duplicate_id":
        first, second = data.draw(st.permutations(ids))[:2]
        _node(d, second)["id"] = first
        return d, first
    if kind == "unknown_op":
        target = data.draw(st.sampled_from(ids))
        _node(d, target)["op"] = "fft"
        return d, target
    if kind == "arity":  # a reader gets two inputs, or a source one that makes no cycle
        dag = graph.to_networkx()
        unrelated = {s: set(ids) - {s} - nx.descendants(dag, s) for s in graph.input_ids()}
        target = data.draw(st.sampled_from(readers + [s for s, u in unrelated.items() if u]))
        node = _node(d, target)
        if node.pop("input", None) is not None:
            node["inputs"] = [graph.inputs_of(target)[0]] * 2
        else:
            node["input"] = data.draw(st.sampled_from(sorted(unrelated[target])))
        return d, target
    if kind == "missing_input":  # a reader lacks input: it is named, not the node it read
        target = data.draw(st.sampled_from(readers))
        node = _node(d, target)
        node.pop("input", None)
        node.pop("inputs", None)
        return d, target
    assert kind == "dangling"
    out = data.draw(st.sampled_from(graph.output_ids()))
    d["nodes"] = [n for n in d["nodes"] if n["id"] != out]
    return d, graph.inputs_of(out)[0]


CORRUPTIONS = ["cycle", "bad_axis", "bad_param", "unknown_input", "duplicate_id",
               "unknown_op", "arity", "missing_input", "dangling"]


@pytest.mark.parametrize("kind", CORRUPTIONS)
@given(graph=chains(max_ops=4), data=st.data())
def test_corrupted_chains_raise_irerror_naming_the_node(
    kind: str, graph: Graph, data: st.DataObject
) -> None:
    d, culprit = _corrupt(graph, kind, data)
    with pytest.raises(IRError) as info:
        Graph.from_dict(d).verify()
    assert f"'{culprit}'" in str(info.value)
    if kind == "cycle":
        assert info.value.node is not None and f"'{info.value.node}'" in str(info.value)
    else:
        assert info.value.node == culprit
