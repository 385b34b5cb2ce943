r"""Import a NIR graph (e.g. exported from snnTorch or Norse) as a ``classifier`` IR op.

The graph must be one chain ``Input → … → Output`` of these patterns (NIR node
types on the left, :mod:`ir.ops.classify` layers on the right):

============================================  =========================================
``Conv2d`` → ``LIF``/``IF``/``CubaLIF``        ``conv2d`` (bias 0, dilation 1, groups 1)
``SumPool2d`` / ``AvgPool2d``                  ``pool`` ``avg`` (a sum pool's ``ph·pw``
                                               is folded into the next weights)
``Flatten``                                    nothing (C, H, W flatten row-major)
``Linear``/``Affine`` → spiking neuron         ``dense``; with a self-loop ``Linear`` on
                                               the neuron (delayed one step): ``recurrent``
``Linear``/``Affine`` → ``LI``/``I``/``CubaLI`` ``integrator`` (the last layer)
============================================  =========================================

Neurons map onto :class:`~ir.ops.classify.LIF` for forward Euler with step
``dt`` (``radarsnn_dt_s`` from the graph metadata, else the ``dt_s`` argument):
``d_v = dt/tau_mem`` (0 for ``IF``/``I``), ``d_u = dt/tau_syn`` (1 without a
synaptic stage), and the input gain — ``r·dt/tau`` (``LIF``/``LI``), ``r·dt``
(``IF``/``I``), ``d_u·w_in·d_v·r`` (``CubaLIF``/``CubaLI``) — is folded into
the layer's incoming (and recurrent) weights.  NIR's ``v > v_threshold`` is
our ``v >= nextafter(v_threshold, +inf)`` exactly; NIR resets to ``v_reset``
(``reset="value"``), or pass ``reset="subtract"`` for frameworks whose
exporters mean subtraction.  Parameters must be uniform within a layer,
``v_leak`` zero and biases zero; anything else is an :class:`IRError` naming
the NIR node.

Examples
--------
>>> import nir, numpy as np, tempfile, pathlib
>>> g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([1, 2, 2])), nir.Flatten(
...     start_dim=0, end_dim=-1, input_type={"input": np.array([1, 2, 2])}),
...     nir.Linear(weight=np.ones((2, 4))), nir.LI(tau=np.full(2, 2.0), r=np.full(2, 2.0),
...     v_leak=np.zeros(2)))
>>> with tempfile.TemporaryDirectory() as d:
...     op = import_classifier(g, pathlib.Path(d) / "w.npz", time_axis="t")
...     w = np.load(pathlib.Path(d) / "w.npz")["layers.0.weight"]
>>> op.layers[0].kind, op.layers[0].dv, float(w[0, 0])
('integrator', 0.5, 1.0)
"""

from __future__ import annotations

import io
from pathlib import Path

import nir
import numpy as np

from backends.atomic import check_output, write_atomic
from backends.nir.reading import read_nir
from ir.errors import ArtifactError, IRError
from ir.ops.classify import LIF, Classifier, Conv2d, Dense, Integrator, Pool, Recurrent

__all__ = ["import_classifier", "read_graph"]

_SPIKING = (nir.LIF, nir.IF, nir.CubaLIF)
_READOUT = (nir.LI, nir.I, nir.CubaLI)


def read_graph(path: str | Path) -> nir.NIRGraph:
    """Read a NIR file within bounds (:func:`backends.nir.reading.read_nir`; no code runs).

    Raises
    ------
    ArtifactError
        Naming the file, the HDF5 node path and the limit (docs/reliability.md).
    """
    return read_nir(path)


def _fail(name: str, message: str) -> IRError:
    return IRError(f"NIR node {name!r}: {message}", node=name)


def _uniform(name: str, node: nir.NIRNode, field: str) -> float:
    values = np.asarray(getattr(node, field), dtype=np.float64).ravel()
    if values.size == 0 or not np.all(values == values[0]) or not np.isfinite(values[0]):
        raise _fail(name, f"{type(node).__name__}.{field} must be one finite value for the "
                          f"whole layer, got {np.unique(values)[:4].tolist()}")
    return float(values[0])


def _neuron(name: str, node: nir.NIRNode, dt: float) -> tuple[float, float, float]:
    """``(du, dv, gain)`` of a NIR neuron node."""
    if isinstance(node, (nir.LIF, nir.LI)):
        tau, r = _uniform(name, node, "tau"), _uniform(name, node, "r")
        du, dv, gain = 1.0, dt / tau, r * dt / tau
    elif isinstance(node, (nir.IF, nir.I)):
        du, dv, gain = 1.0, 0.0, _uniform(name, node, "r") * dt
    else:  # CubaLIF / CubaLI
        du = dt / _uniform(name, node, "tau_syn")
        dv = dt / _uniform(name, node, "tau_mem")
        gain = du * _uniform(name, node, "w_in") * dv * _uniform(name, node, "r")
    if hasattr(node, "v_leak") and _uniform(name, node, "v_leak") != 0.0:
        raise _fail(name, "v_leak must be 0 (the classifier's neurons have no bias)")
    if not (0.0 <= du <= 1.0 and 0.0 <= dv <= 1.0):
        raise _fail(name, f"time constants give decays d_u = {du:g}, d_v = {dv:g} outside "
                          f"[0, 1] at dt = {dt:g} s; use a smaller dt_s or larger tau")
    return du, dv, gain


def _lif(name: str, node: nir.NIRNode, du: float, dv: float, reset: str) -> LIF:
    v_th = float(np.nextafter(_uniform(name, node, "v_threshold"), np.inf))
    if v_th <= 0:
        raise _fail(name, f"v_threshold {v_th:g} must be positive")
    return LIF(du=du, dv=dv, v_th=v_th, reset=reset, v_reset=_uniform(name, node, "v_reset"))


def _chain(graph: nir.NIRGraph) -> tuple[list[str], dict[str, str]]:
    """The main chain of node names and the self-loop ``Linear`` of each recurrent neuron."""
    succ: dict[str, list[str]] = {k: [] for k in graph.nodes}
    for a, b in graph.edges:
        succ[a].append(b)
    inputs = [k for k, n in graph.nodes.items() if isinstance(n, nir.Input)]
    if len(inputs) != 1:
        raise IRError(f"NIR graph: a classifier needs exactly one Input node, got {inputs}")
    chain, loops, cur = [inputs[0]], {}, inputs[0]
    while not isinstance(graph.nodes[cur], nir.Output):
        nxt = [b for b in succ[cur] if succ[b] != [cur]]
        for b in succ[cur]:
            if succ[b] == [cur]:
                loops[cur] = b
        if len(nxt) != 1 or nxt[0] in chain:
            raise _fail(cur, f"a classifier is one chain Input -> ... -> Output, but this node "
                             f"feeds {succ[cur]}")
        cur = nxt[0]
        chain.append(cur)
    return chain, loops


def _weight(name: str, node: nir.NIRNode) -> np.ndarray:
    bias = getattr(node, "bias", None)
    if bias is not None and np.any(np.asarray(bias) != 0):
        raise _fail(name, f"{type(node).__name__} has a non-zero bias; the classifier's layers "
                          "have none (fold it into a threshold or retrain without bias)")
    return np.asarray(node.weight, dtype=np.float64)


def _pair(name: str, value: object, what: str) -> tuple[int, int]:
    a = np.atleast_1d(np.asarray(value)).astype(np.int64)
    if a.size == 1:
        a = np.repeat(a, 2)
    if a.size != 2:
        raise _fail(name, f"{what} {a.tolist()} is not a pair")
    return int(a[0]), int(a[1])


def import_classifier(
    graph: nir.NIRGraph | str | Path,
    weights_path: str | Path,
    *,
    dt_s: float = 1.0,
    reset: str = "value",
    encoding: dict | None = None,
    time_axis: str = "frame",
    map_axes: tuple[str, str] = ("range", "doppler"),
) -> Classifier:
    """Turn a NIR graph into a ``classifier`` op and write its weights npz.

    Parameters
    ----------
    graph : nir.NIRGraph or path
        The graph, or a ``.nir`` file read with :func:`read_graph` (bounded).
    weights_path : path
        Where the weights ``.npz`` is written, atomically (keys ``layers.<i>.weight`` /
        ``.recurrent``); the op's ``weights`` field names it.
    dt_s : float
        Step duration when the graph has no ``radarsnn_dt_s`` metadata.
    reset : {"value", "subtract"}
        What a spike does in the imported LIF layers (NIR itself resets to ``v_reset``).
    encoding : dict, optional
        The op's encoding (default ``{"kind": "real"}``); its channel count must match the
        Input's first dimension.
    time_axis, map_axes : str
        As in :class:`~ir.ops.classify.Classifier`.

    Returns
    -------
    Classifier
        Validated against the weights (``check_weights``).

    Raises
    ------
    IRError
        Naming the NIR node that has no classifier form, or for a graph radarsnn exported
        (read those with :func:`backends.nir.import_nir`).
    ArtifactError
        ``weights_path`` is no place for a file (a device, a folder), or cannot be written.
    """
    if not isinstance(graph, nir.NIRGraph):
        graph = read_graph(graph)
    if isinstance(graph.metadata, dict) and "radarsnn_round_trip" in graph.metadata:
        raise IRError("NIR graph: exported by radarsnn (metadata radarsnn_round_trip); read it "
                      "back with backends.nir.import_nir (radarsnn import-nir), which restores "
                      "its spiking networks exactly, not as a classifier op")
    meta_dt = graph.metadata.get("radarsnn_dt_s") if isinstance(graph.metadata, dict) else None
    dt = float(meta_dt.decode() if isinstance(meta_dt, bytes) else meta_dt) if meta_dt else dt_s
    chain, loops = _chain(graph)
    nodes = graph.nodes
    shape = tuple(int(n) for n in nodes[chain[0]].output_type["output"])
    if len(shape) != 3:
        raise _fail(chain[0], f"Input shape {shape} must be (channels, H, W)")
    layers, arrays, gain_next = [], {}, 1.0
    i = 1
    while i < len(chain) - 1:
        name, node = chain[i], nodes[chain[i]]
        k = len(layers)
        if isinstance(node, (nir.SumPool2d, nir.AvgPool2d)):
            size = _pair(name, node.kernel_size, "kernel_size")
            if _pair(name, node.stride, "stride") != size or any(
                    _pair(name, node.padding, "padding")):
                raise _fail(name, "pooling must have stride = kernel_size and no padding")
            layers.append(Pool(mode="avg", size=size))
            if isinstance(node, nir.SumPool2d):
                gain_next *= size[0] * size[1]
            i += 1
            continue
        if isinstance(node, nir.Flatten):
            i += 1
            continue
        if not isinstance(node, (nir.Conv2d, nir.Linear, nir.Affine)) or i + 1 >= len(chain):
            raise _fail(name, f"{type(node).__name__} has no classifier layer form here; "
                              "expected Conv2d/Linear/Affine followed by a neuron, a pool or "
                              "a Flatten")
        neuron_name, neuron = chain[i + 1], nodes[chain[i + 1]]
        if not isinstance(neuron, _SPIKING + _READOUT):
            raise _fail(neuron_name, f"{type(neuron).__name__} after {name!r}: expected a "
                                     "LIF/IF/CubaLIF layer or an LI/I/CubaLI readout")
        du, dv, gain = _neuron(neuron_name, neuron, dt)
        w = _weight(name, node) * gain * gain_next
        gain_next = 1.0
        if isinstance(node, nir.Conv2d):
            if _pair(name, node.dilation, "dilation") != (1, 1) or int(node.groups) != 1:
                raise _fail(name, "Conv2d needs dilation 1 and groups 1")
            padding = node.padding
            if isinstance(padding, str):
                padding = 0 if padding == "valid" else tuple(n // 2 for n in w.shape[2:])
            layers.append(Conv2d(channels=w.shape[0], kernel=w.shape[2:],
                                 stride=_pair(name, node.stride, "stride"),
                                 padding=_pair(name, padding, "padding"),
                                 neuron=_lif(neuron_name, neuron, du, dv, reset)))
        elif isinstance(neuron, _READOUT):
            if i + 2 != len(chain) - 1:
                raise _fail(neuron_name, "a non-spiking readout must be the last layer")
            layers.append(Integrator(units=w.shape[0], du=du, dv=dv))
        elif neuron_name in loops:
            rec = _weight(loops[neuron_name], nodes[loops[neuron_name]]) * gain
            arrays[f"layers.{k}.recurrent"] = rec
            layers.append(Recurrent(units=w.shape[0],
                                    neuron=_lif(neuron_name, neuron, du, dv, reset)))
        else:
            layers.append(Dense(units=w.shape[0], neuron=_lif(neuron_name, neuron, du, dv,
                                                              reset)))
        arrays[f"layers.{k}.weight"] = w
        i += 2
    if not layers or layers[-1].kind != "integrator":
        raise _fail(chain[-1], "the graph must end in a Linear -> LI/I/CubaLI readout")
    op = Classifier(num_classes=layers[-1].units, weights=str(weights_path),
                    layers=tuple(layers), encoding=encoding or {"kind": "real"},
                    time_axis=time_axis, map_axes=map_axes)
    if op.encoding.channels != shape[0]:
        raise _fail(chain[0], f"Input has {shape[0]} channels but the encoding "
                              f"{op.encoding.kind!r} gives {op.encoding.channels}; pass a "
                              "matching encoding")
    arrays = op.check_weights("classifier", shape[1:], arrays)
    npz = io.BytesIO()
    np.savez(npz, **arrays)
    try:  # whole or not at all, at the path the op names (np.savez would add ".npz")
        write_atomic(check_output(weights_path), npz.getvalue())
    except OSError as exc:
        raise ArtifactError(f"cannot write the classifier weights to {weights_path}: "
                            f"{exc.strerror or exc}") from exc
    return op
