r"""Numpy code of the host segments: one ``compute(x)`` per IR node, constants folded.

Each op type has one emitter in the explicit registry :data:`HOST_EMITTERS`
(op class → ``emitter(pkg, module, node_id, op, in_type) -> body``); the code
repeats what :data:`ir.interpreter.EVAL_REGISTRY` computes (``radar.dsp``,
``radar.windows``, ``radar.cfar``) with every parameter resolved at emit time:
window taps, DFT bins, linear matrices and the CFAR window geometry (training
mask, per-cell training counts and effective ``k``) are stored in
``weights.npz``.  Ops without an emitter are refused with
:class:`~ir.errors.CompileError` naming the node.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from backends.emit.package import PackageBuilder
from backends.emit.render import Code, comment, indent, join, lit, render, template
from ir.errors import CompileError
from ir.ops import (
    CFAR,
    DFT,
    AdcInput,
    Add,
    Classifier,
    Cluster,
    Input,
    Linear,
    Log,
    Magnitude,
    Op,
    Output,
    Sum,
    Threshold,
    Track,
    Window,
)
from ir.types import TensorType
from radar.cfar_window import _mask, effective_k, training_counts
from radar.dsp import dft_bins
from radar.windows import window_coefficients

__all__ = ["HOST_EMITTERS", "NOT_EMITTED", "emit_host"]

HostEmitter = Callable[[PackageBuilder, str, str, Op, TensorType], Code]


def _window_taps(kind: str, t: TensorType, axis: str) -> np.ndarray:
    ax = t.index(axis)
    w = window_coefficients(kind, t.shape[ax])
    shape = [1] * len(t.shape)
    shape[ax] = w.size
    return w.reshape(shape)


def _window(pkg: PackageBuilder, module: str, node: str, op: Window, t: TensorType) -> Code:
    key = pkg.store(module, "compute", 0, "window", _window_taps(op.kind, t, op.axis))
    return render("key = $k\nreturn _kernels.as_float(x) * _kernels.array(key, 0, \"window\")",
                  k=lit(key))


def _dft(pkg: PackageBuilder, module: str, node: str, op: DFT, t: TensorType) -> Code:
    ax = lit(t.index(op.axis))
    n_in = t.shape[t.index(op.axis)]
    n = lit(op.n_fft or n_in)
    lines = [render("x = _kernels.as_float(x)")]
    if op.window is not None:
        key = pkg.store(module, "compute", 0, "window", _window_taps(op.window, t, op.axis))
        lines.append(render("key = $k\nx = x * _kernels.array(key, 0, \"window\")", k=lit(key)))
    if op.keep == "positive":
        lines.append(render("if np.iscomplexobj(x):\n    spectrum = np.fft.fft(x, n=$n, axis=$ax)\n"
                            "else:\n    spectrum = np.fft.rfft(x, n=$n, axis=$ax)", n=n, ax=ax))
    else:
        lines.append(render("spectrum = np.fft.fft(x, n=$n, axis=$ax)", n=n, ax=ax))
    if op.keep == "all" and not op.shift:
        lines.append(render("return spectrum"))
    else:
        key = pkg.store(module, "compute", 0, "bins",
                        dft_bins(op.n_fft or n_in, keep=op.keep, shift=op.shift))
        lines.append(render("key = $k\nbins = _kernels.array(key, 0, \"bins\")\n"
                            "return np.take(spectrum, bins, axis=$ax)",
                            k=lit(key), ax=ax))
    return join(lines)


def _linear(pkg: PackageBuilder, module: str, node: str, op: Linear, t: TensorType) -> Code:
    matrix = np.asarray(op.matrix, dtype=np.float64)
    if op.matrix_imag is not None:
        matrix = matrix + 1j * np.asarray(op.matrix_imag, dtype=np.float64)
    key = pkg.store(module, "compute", 0, "matrix", matrix)
    return render("key = $k\nmatrix = _kernels.array(key, 0, \"matrix\")\n"
                  "return np.moveaxis(np.tensordot(matrix, x, axes=([1], [$ax])), 0, $ax)",
                  k=lit(key), ax=lit(t.index(op.axis)))


def _sum(pkg: PackageBuilder, module: str, node: str, op: Sum, t: TensorType) -> Code:
    return render("return x.sum(axis=$ax)", ax=lit(t.index(op.axis)))


def _magnitude(pkg: PackageBuilder, module: str, node: str, op: Magnitude,
               t: TensorType) -> Code:
    expr = {"l2": "np.abs(z)", "l1": "np.abs(z.real) + np.abs(z.imag)",
            "square": "z.real * z.real + z.imag * z.imag"}[op.kind]
    return render("z = np.asarray(x, dtype=np.complex128)\n"
                  "return np.asarray(" + expr + ", dtype=np.float64)")


def _log(pkg: PackageBuilder, module: str, node: str, op: Log, t: TensorType) -> Code:
    if t.domain == "power":
        head = render("arr = np.asarray(x)\nif np.iscomplexobj(arr) or np.any(arr < 0):\n"
                      "    raise ValueError(\"log of powers needs real values >= 0\")\n"
                      "arr = arr.astype(np.float64, copy=False)")
        factor = 10.0
    else:
        head = render("arr = np.abs(np.asarray(x)).astype(np.float64, copy=False)")
        factor = 20.0
    return join([head, render("with np.errstate(divide=\"ignore\"):\n"
                              "    return np.maximum($f * np.log10(arr), $floor)",
                              f=lit(factor), floor=lit(float(op.floor_db)))])


def _threshold(pkg: PackageBuilder, module: str, node: str, op: Threshold,
               t: TensorType) -> Code:
    cmp = "x > $v" if op.strict else "x >= $v"
    return render("return " + cmp, v=lit(float(op.value)))


def _cfar(pkg: PackageBuilder, module: str, node: str, op: CFAR, t: TensorType) -> Code:
    win = op.window(node, t)
    src = tuple(t.index(a) for a in win.axes)
    dst = tuple(range(-len(src), 0))
    mask = _mask(win.guard, win.train)
    n_total = int(mask.sum())
    map_shape = tuple(t.shape[i] for i in src)
    counts = training_counts(map_shape, guard=win.guard, train=win.train, edge=win.edge)
    k = int(op.k) if op.kind == "os" else 0
    k_eff = effective_k(k, counts, n_total) if op.kind == "os" else np.zeros_like(counts)
    for part, arr in (("mask", mask), ("counts", counts), ("k_eff", k_eff)):
        key = pkg.store(module, "compute", 0, part, np.asarray(arr))
    geometry = dict(kind=lit(op.kind), k=lit(k), reach=lit(tuple(
        int(g + r) for g, r in zip(win.guard, win.train, strict=True))),
        wrap=lit(tuple(e == "wrap" for e in win.edge)), key=lit(key))
    return render(
        "moved = np.moveaxis(x, $src, $dst)\n"
        "arr = np.asarray(moved).astype(np.float64, copy=False)\n"
        "key = $key\nparts = (\"mask\", \"counts\", \"k_eff\")\n"
        "mask, counts, k_eff = (_kernels.array(key, 0, part) for part in parts)\n"
        "noise = _kernels.cfar_noise(arr, $kind, $k, mask, counts, k_eff, $reach, $wrap)\n"
        "threshold = $alpha * noise\n"
        "detections = np.asarray(moved, dtype=np.float64) > threshold\n"
        "return np.moveaxis(detections, $dst, $src)", src=lit(src), dst=lit(dst),
        alpha=lit(float(op.alpha_for(win.n_train))), **geometry)


def _add(pkg: PackageBuilder, module: str, node: str, op: Add, t: TensorType) -> Code:
    return render("return x + y")


def _output(pkg: PackageBuilder, module: str, node: str, op: Output, t: TensorType) -> Code:
    return render("return x")


#: Host emitters by op class.
HOST_EMITTERS: dict[type[Op], HostEmitter] = {
    Window: _window,
    DFT: _dft,
    Linear: _linear,
    Sum: _sum,
    Magnitude: _magnitude,
    Log: _log,
    Add: _add,
    Threshold: _threshold,
    CFAR: _cfar,
    Output: _output,
}

#: Op types the generated numpy package cannot run on the host, and why (emit refuses them,
#: naming the node; every op of ``ir.ops.OP_REGISTRY`` is here or in :data:`HOST_EMITTERS`).
NOT_EMITTED: dict[type[Op], str] = {
    Input: "a graph input: the package's run() takes it as an array",
    AdcInput: "a graph input: the package's run() takes it as an array",
    Classifier: "its weights live in a file beside the chain; the package would have to ship "
                "and load them (not yet)",
    Cluster: "needs scikit-learn's DBSCAN, which the package does not depend on",
    Track: "a stateful tracker across frames; the package runs one frame per call",
}


def emit_host(pkg: PackageBuilder, node: str, op: Op, in_type: TensorType,
              emitters: dict[type[Op], HostEmitter] = HOST_EMITTERS) -> str:
    """Write ``compute(x)`` of host node ``node`` into its stage module; return the module.

    Raises
    ------
    CompileError
        If the op type has no host emitter (naming the node and the supported ops).
    """
    emitter = emitters.get(type(op))
    if emitter is None:
        known = sorted(cls.op_name() for cls in emitters)
        raise CompileError(f"node {node!r}: op {op.op_name()!r} has no numpy host emitter; the "
                           f"generated simulator supports host ops {known}; lower the node to "
                           "spikes or run the program with backends.reference", node=node)
    module = pkg.stage(node)
    pkg.names.setdefault("compute", {})[f"{module}.compute"] = node
    body = emitter(pkg, module, node, op, in_type)
    pkg.add(module, render(template("host.tmpl"), op=lit(op.op_name()), node=comment(node),
                           body=indent(body)))
    return module
