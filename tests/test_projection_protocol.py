"""The projection protocol: every kind answers for itself, and no caller dispatches on kind.

Hand-worked numbers (the values the old isinstance/kind dispatch gave):

* matrix ``x{rep: 3, i: 2} -> y{rep: 3, o: 2}``, ``W = [[1, 0], [2, 3]]``: repetitions
  ``3 = 6 / 2``, repetition axes ``{rep}``, nominal instances ``3 * 3 = 9``, wired ``9``;
* sparse matrix with a duplicate COO entry and a stored zero: ``n_synapses`` counts the
  two non-zero values, the wired pattern counts the one distinct live entry;
* stencil ``K = [1, 1, 1]`` clipped on ``r: 4``: repetitions 1, nominal ``4 * 3 = 12``,
  wired ``2 + 3 + 3 + 2 = 10``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from compiler.snn import MatrixProjection, Population, SpikingNetwork, StencilProjection
from compiler.snn.projections import PROTOCOL, ProjectionKind, weights_of, with_weights
from ir.errors import NetworkError

ROOT = Path(__file__).resolve().parents[1]
KINDS = (MatrixProjection, StencilProjection)
KIND_TAGS = {k.kind for k in KINDS}
KIND_NAMES = {k.__name__ for k in KINDS}
#: The projection modules themselves may look at their own kind.
PROJECTION_MODULES = {"compiler/snn/projections.py", "compiler/snn/matrix_projection.py",
                      "compiler/snn/stencil_projection.py", "compiler/snn/projection_checks.py"}
#: Sites allowed to name kind tags, with the reason.
ALLOWED = {
    "backends/artifact.py": "the artifact reader's registry maps the serialized `kind` tag "
                            "back to its class (decoding, not dispatch)",
    "backends/crosscheck/chipnet.py": "the cross-check worker runs in another Python and "
                                      "reads the artifact's JSON: it decodes the serialized "
                                      "`kind` tag (no project classes there)",
}

X = Population(id="x", shape={"rep": 3, "i": 2}, source=True)
Y = Population(id="y", shape={"rep": 3, "o": 2})
B = Population(id="b", shape={"r": 4})


def _matrix(**kw) -> MatrixProjection:
    return MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
                            **({"weights": np.array([[1.0, 0.0], [2.0, 3.0]])} | kw))


def _sparse() -> MatrixProjection:
    return MatrixProjection(id="s", source="x", target="y", contract=("i",), produce=("o",),
                            rows=[0, 0, 1], cols=[1, 1, 0], values=[2.0, 1.0, 0.0],
                            n_in_out=(2, 2), delays=np.array([0, 1, 4]))


def _stencil(**kw) -> StencilProjection:
    return StencilProjection(id="k", source="b", target="b", axes=("r",),
                             **({"kernel": np.ones(3), "edge": ("clip",)} | kw))


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_implements_the_whole_protocol(kind) -> None:
    proj = _matrix() if kind is MatrixProjection else _stencil()
    missing = [m for m in PROTOCOL if not hasattr(proj, m)]
    assert not missing, f"{kind.__name__} lacks {missing}"
    assert isinstance(proj, ProjectionKind)


def test_dense_matrix_answers() -> None:
    w = _matrix()
    assert w.stored_weights().tolist() == [[1.0, 0.0], [2.0, 3.0]]
    assert (w.repetitions(X), w.repetition_axes(Y)) == (3, {"rep"})
    assert (w.n_synapse_instances(X, Y), w.wired_synapses(X, Y), w.min_delay()) == (9, 9, 0)
    w2 = w.with_weights(np.full((2, 2), 0.5))
    assert w2.weights.tolist() == [[0.5, 0.5], [0.5, 0.5]] and w2.id == "w"
    assert weights_of(w) is w.stored_weights() and with_weights(w, w.weights).weights is not None


def test_sparse_matrix_answers() -> None:
    s = _sparse()
    assert s.stored_weights().tolist() == [2.0, 1.0, 0.0]
    assert s.n_synapses == 2 and s.n_synapse_instances(X, Y) == 6
    assert s.wired_synapses(X, Y) == 3          # (0, 1) once: the duplicate entries merge
    assert s.min_delay() == 0                   # the stored zero (delay 4) is no synapse
    assert s.with_weights(np.array([1.0, 1.0, 1.0])).values.tolist() == [1.0, 1.0, 1.0]


def test_stencil_answers() -> None:
    k = _stencil(delays=np.array([2, 1, 3]))
    assert k.stored_weights().tolist() == [1.0, 1.0, 1.0]
    assert (k.repetitions(B), k.repetition_axes(B)) == (1, None)
    assert (k.n_synapse_instances(B, B), k.wired_synapses(B, B), k.min_delay()) == (12, 10, 1)
    assert k.with_weights(np.array([0.0, 2.0, 0.0])).n_taps == 1
    assert _stencil(kernel=np.zeros(3)).min_delay() is None


def test_check_axes_is_each_kinds_own() -> None:
    with pytest.raises(NetworkError, match="repetition axes differ"):
        _matrix().check_axes(X, Population(id="y", shape={"rep": 2, "o": 2}))
    with pytest.raises(NetworkError, match="same axes and sizes"):
        _stencil().check_axes(B, Population(id="c", shape={"r": 5}))
    _matrix().check_axes(X, Y)
    _stencil().check_axes(B, B)


def test_network_counts_through_the_protocol() -> None:
    net = SpikingNetwork(name="n", n_steps=4, populations=[
        X, Y, Population(id="a", shape={"r": 4}, source=True), B],
        projections=[_matrix(), StencilProjection(id="k", source="a", target="b", axes=("r",),
                                                  kernel=np.ones(3), edge=("clip",))])
    assert net.n_synapse_instances() == 9 + 12 and net.n_synapses == 3 + 3


# ------------------------------------------------------------------ no dispatch on kind
def _names(node: ast.AST) -> set[str]:
    return {n.id if isinstance(n, ast.Name) else n.attr
            for n in ast.walk(node) if isinstance(n, ast.Name | ast.Attribute)}


def _tags(node: ast.AST) -> set[str]:
    return {n.value for n in ast.walk(node)
            if isinstance(n, ast.Constant) and isinstance(n.value, str)} & KIND_TAGS


def dispatch_sites(tree: ast.AST) -> list[tuple[int, str]]:
    """``isinstance``/``hasattr`` on projection kinds, ``.kind`` compared with a projection
    tag, and dict tables keyed by projection tags."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            if node.func.id == "isinstance" and len(node.args) == 2 \
                    and _names(node.args[1]) & KIND_NAMES:
                found.append((node.lineno, "isinstance on a projection kind"))
            if node.func.id == "hasattr" and len(node.args) == 2 and isinstance(
                    node.args[1], ast.Constant) and node.args[1].value in {"contract", "kernel"}:
                found.append((node.lineno, "hasattr probing a projection kind"))
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(isinstance(s, ast.Attribute) and s.attr == "kind" for s in sides) \
                    and any(_tags(s) for s in sides):
                found.append((node.lineno, "`.kind` compared with a projection tag"))
        elif isinstance(node, ast.Dict) and node.keys and all(
                isinstance(k, ast.Constant) and k.value in KIND_TAGS for k in node.keys):
            found.append((node.lineno, "a table keyed by projection kind tags"))
    return found


def _sources():
    for top in ("compiler", "backends"):
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel not in PROJECTION_MODULES:
                yield rel, ast.parse(path.read_text(), rel)


def test_no_projection_kind_dispatch_outside_the_projection_modules() -> None:
    bad = [f"{rel}:{line}: {why}" for rel, tree in _sources() if rel not in ALLOWED
           for line, why in dispatch_sites(tree)]
    assert not bad, "dispatch on projection kind (use the protocol or a type table):\n" + \
        "\n".join(bad)


def test_the_walker_catches_each_form_and_the_allowlist_is_live() -> None:
    code = ('isinstance(p, MatrixProjection)\nif p.kind == "stencil": pass\n'
            'T = {"matrix": f, "stencil": g}\nhasattr(q, "contract")\nk in ("matrix",)\n'
            'seg.kind == "spiking"\n')
    assert sorted(line for line, _ in dispatch_sites(ast.parse(code))) == [1, 2, 3, 4]
    for rel in ALLOWED:
        assert dispatch_sites(ast.parse((ROOT / rel).read_text())), f"{rel}: stale allowlist"
