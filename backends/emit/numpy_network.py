r"""Numpy code of a spiking network's stage functions: neuron updates, deliveries, ports.

The emitted code follows ``backends.reference`` step mode operation for
operation (:mod:`compiler.snn.neurons` is the equation):

* every population's update is written out per phase of its schedule with
  its constants folded (``du = 0`` gives ``u = u + current``, ``dv = 0`` drops
  the decay, a zero bias disappears, integer decays become
  ``trunc(x·keep/4096)``);
* every projection becomes a ``deliver_*`` function over the weights of the
  reference plan (:func:`backends.reference.build_plan`): the same delay
  classes, the same dense or CSR operands, the same summation order;
* encoders and decoders repeat :mod:`compiler.snn.coding`'s formulas with the
  code's constants folded; a decoder with per-index gains divides by them as
  :mod:`backends.reference.decoding` does (``(scale·… + offset) / gains``, before
  ``combine``).

Per-kind writers (deliveries) are picked from a table keyed by the projection
type, never by testing its kind.  The step loop that calls them is
:mod:`backends.emit.numpy_loop`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from backends.emit.package import PackageBuilder
from backends.emit.render import Code, comment, ident, indent, join, lit, render, template
from backends.reference.input_range import PER_PART
from backends.reference.neuron import StepParams
from compiler.snn.coding import N_PARTS, Decoder, Encoder, LatencyCode
from compiler.snn.network import Population
from compiler.snn.neurons import DECAY_ONE
from compiler.snn.projections import MatrixProjection, StencilProjection
from compiler.snn.resonator import ResonatorParams
from ir.errors import CompileError

__all__ = ["DECODER_INPUT", "decode_function", "deliver_function", "encode_function",
           "node_of", "update_function"]


def node_of(item: Population | MatrixProjection, fallback: str) -> str:
    """The IR node a population or projection came from (``fallback`` without one)."""
    return str(item.origin.get("node") or fallback)


# --------------------------------------------------------------------- neuron update
def _decayed(var: str, d: float, integer: bool) -> Code:
    """``(1 - d)·var`` folded: the variable itself, zeros, or a product."""
    name = ident(var)
    if integer:
        keep = DECAY_ONE - round(d * DECAY_ONE)
        if keep == DECAY_ONE:
            return name
        if keep == 0:
            return render("np.zeros_like($x)", x=name)
        return render("_kernels.decay_int($x, $keep)", x=name, keep=lit(keep))
    if d == 0.0:
        return name
    if d == 1.0:
        return render("np.zeros_like($x)", x=name)
    return render("$keep * $x", keep=lit(1.0 - d), x=name)


def _scaled(sp_: StepParams, value: float | int) -> Code:
    """A threshold, reset or bias constant, times the per-neuron scales ``c`` if any."""
    return lit(value) if sp_.scale is None else render("$x * c", x=lit(value))


def _phase(sp_: StepParams, bias: float | int, input_on: bool, spiking_on: bool) -> Code:
    lines = []
    if input_on:
        lines.append(render("u = $u + current", u=_decayed("u", sp_.du, sp_.integer)))
        term = render("u") if bias == 0 else render("(u + $b)", b=_scaled(sp_, bias))
    else:
        lines.append(render("u = np.zeros_like(u)"))
        term = lit(bias) if bias == 0 else _scaled(sp_, bias)
    lines.append(render("v = $v + $term", v=_decayed("v", sp_.dv, sp_.integer), term=term))
    lines.append(render("spikes = v >= $th", th=_scaled(sp_, sp_.v_th)) if spiking_on
                 else render("spikes = np.zeros(v.shape, bool)"))
    return join(lines)


def update_function(pkg: PackageBuilder, module: str, pop: Population, sp_: StepParams) -> str:
    """Write the folded neuron update of ``pop``; return its function name."""
    if isinstance(pop.params, ResonatorParams):
        raise CompileError(f"population {pop.id!r}: the numpy emitter has no resonator update "
                           "(motif 'resonator'); simulate it with backends.reference or "
                           "compile that node with motif 'time'", node=pop.origin.get("node"))
    fn = pkg.function(module, "update_", pop.id)
    segs = sp_.spans
    if len(segs) == 1:
        phases = indent(_phase(sp_, segs[0].bias, segs[0].input_on, segs[0].spiking_on))
    else:
        parts = []
        for i, s in enumerate(segs):
            head = (render("if t < $e:", e=lit(s.stop)) if i == 0 else
                    render("else:") if i == len(segs) - 1 else
                    render("elif t < $e:", e=lit(s.stop)))
            parts += [head, indent(_phase(sp_, s.bias, s.input_on, s.spiking_on))]
        phases = indent(join(parts))
    if sp_.scale is not None:  # per-neuron scales, one per neuron (broadcast over frames)
        key = pkg.store(module, fn, 0, "scale", sp_.scale)
        phases = join([indent(render("c = _kernels.array($k, 0, 'scale')", k=lit(key))),
                       phases])
    reset = {"fire_once": render("spikes &= ~fired"),
             "value": render("v = np.where(spikes, $r, v)", r=_scaled(sp_, sp_.v_reset)),
             "subtract": render("v = np.where(spikes, v - $th, v)", th=_scaled(sp_, sp_.v_th))}
    summary = render("du=$du, dv=$dv, $n phase(s)\n    # v_th=$th, reset $reset", du=lit(sp_.du),
                     dv=lit(sp_.dv), th=lit(sp_.v_th), n=lit(len(segs)), reset=lit(sp_.reset))
    pkg.add(module, render(template("update.tmpl"), fn=ident(fn), summary=summary,
                           pop=comment(pop.id), phases=phases,
                           reset=indent(reset[sp_.reset])))
    return fn


# --------------------------------------------------------------------- deliveries
def deliver_function(pkg: PackageBuilder, module: str, proj, dl, pops: dict, integer: bool) -> str:
    """Write the delivery of projection ``proj``; return its function name.

    The writer is picked by the projection's type from :data:`_DELIVERY_WRITERS`.
    """
    fn = pkg.function(module, "deliver_", proj.id)
    src, tgt = pops[proj.source], pops[proj.target]
    _DELIVERY_WRITERS[type(proj)](pkg, module, fn, proj, dl, src, tgt, lit(bool(integer)))
    return fn


def _deliver_stencil(pkg: PackageBuilder, module: str, fn: str, proj, dl, src: Population,
                     tgt: Population, integer_: Code) -> None:
    key = ""
    for k in range(len(dl.delays)):
        for part, arr in (("weights", dl.tap_weights[k]), ("offsets", dl.offsets[k]),
                          ("deltas", dl.deltas[k]), ("interior", dl.interior[k]),
                          ("base_of", dl.base_of)):
            key = pkg.store(module, fn, k, part, arr)
    pkg.add(module, render(
        template("stencil.tmpl"), fn=ident(fn), delays=lit(dl.delays), proj=comment(proj.id),
        key=lit(key), map_axes=lit(dl.map_axes), wrap=lit(dl.wrap),
        src_axis_of=lit(dl.src_axis_of), src_dims=lit(dl.src_dims),
        tgt_dims=lit(dl.tgt_dims), integer=integer_))


def _deliver_matrix(pkg: PackageBuilder, module: str, fn: str, proj, dl, src: Population,
                    tgt: Population, integer_: Code) -> None:
    rep_axes = tuple(a for a in tgt.axes if a not in proj.produce)
    index = ident("index_" + fn.removeprefix("deliver_"))
    if sp.issparse(dl.weights[0]):
        for k, w in enumerate(dl.weights):
            w = w.tocsr()
            w.sort_indices()
            for part, arr in (("indptr", w.indptr.astype(np.int64)),
                              ("indices", w.indices.astype(np.int64)), ("data", w.data)):
                key = pkg.store(module, fn, k, part, arr)
        body = render(
            "    key = $key\n    parts = (\"indptr\", \"indices\", \"data\")\n"
            "    csr = tuple(_kernels.array(key, k, part) for part in parts)\n"
            "    return _kernels.sparse_current(events, n_batch, (*csr, $n_out), "
            "$index(), $integer)", key=lit(key), n_out=lit(dl.n_out), index=index,
            integer=integer_)
    else:
        key = pkg.store(module, fn, 0, "w", dl.weights[0])
        body = render(
            "    key = $key\n    w = _kernels.array(key, k, \"w\")\n"
            "    return _kernels.matrix_current(events, "
            "n_batch, w, $index(), $blas, $integer)", key=lit(key), index=index,
            blas=lit(bool(dl.blas_events)), integer=integer_)
    pkg.add(module, render(
        template("deliver.tmpl"), fn=ident(fn), index=index, delays=lit(dl.delays),
        proj=comment(proj.id), src_dims=lit(src.dims),
        rep_positions=lit(tuple(src.axes.index(a) for a in rep_axes)),
        col_positions=lit(tuple(src.axes.index(a) for a in proj.contract)),
        n_reps=lit(int(dl.n_reps)), block_shape=lit(tuple(int(x) for x in dl.block_shape)),
        to_target=lit(tuple(int(x) for x in dl.to_target)), body=body))


#: Delivery writers by projection type (the emitter's own table, after the reference plan's).
_DELIVERY_WRITERS = {MatrixProjection: _deliver_matrix, StencilProjection: _deliver_stencil}


# --------------------------------------------------------------------- ports
def encode_function(pkg: PackageBuilder, module: str, enc: Encoder, pop: Population,
            n_steps: int) -> str:
    """Write the encoder of port ``enc``; return its function name."""
    fn = pkg.function(module, "encode_", enc.port)
    code = enc.code
    names = pop.axes[:-1] if N_PARTS[enc.split] else pop.axes
    axes = tuple(1 + names.index(a) for a in enc.normalize_axes)
    if isinstance(code, LatencyCode):
        lo, hi = code.x_min, code.x_max
        lines = []
        if code.kind == "log":
            lo, hi = float(np.log(lo)), float(np.log(hi))
            lines.append(render("x = np.log(x)"))
        ramp = dict(hi=lit(float(hi)), span=lit(float(hi - lo)),
                    t_span=lit(code.t_max - code.t_min), t0=lit(code.t_min))
        lines.append(render("t = ($hi - x) / $span * $t_span", **ramp) if code.t_min == 0 else
                     render("t = $t0 + ($hi - x) / $span * $t_span", **ramp))
        if code.rounding == "dither":
            lines.append(render("t = t + _kernels.dither_offsets(t.shape[-1])"))
        lines.append(render("steps = np.rint(t).astype(np.int64)") if code.rounding == "nearest"
                     else render("steps = np.floor(t).astype(np.int64)"))
        lines.append(render("return _kernels.latency_train(steps, $limit, $n)",
                            limit=lit(min(code.t_max, n_steps)), n=lit(n_steps)))
        summary = render("latency code, $kind", kind=lit(code.kind))
    else:
        lines = [render("rates = $r * (x - $lo) / $span", r=lit(code.max_rate),
                        lo=lit(code.x_min), span=lit(code.x_max - code.x_min)),
                 render("return rates.ravel()")]
        summary = render("rate code, max rate $r", r=lit(code.max_rate))
    pkg.add(module, render(
        template("encode.tmpl"), fn=ident(fn), summary=summary, port=comment(enc.port),
        pop=comment(pop.id), normalize_axes=lit(axes), split=lit(enc.split),
        check=indent(_range_check(enc, n_steps)), x_min=lit(code.x_min), x_max=lit(code.x_max),
        body=indent(join(lines))))
    return fn


def _range_check(enc: Encoder, n_steps: int) -> Code:
    """The out-of-range check of ``enc`` (``backends.reference.input_range``'s rule, folded).

    Latency, nearest rounding: ``parts > x*`` with ``x* = value_of(t_min - 1/2)`` (``>=``
    when ``rint(t_min - 1/2) < t_min``); floor rounding: ``parts > x_max``; rate:
    one more spike than ``x_max`` gives; a one-step window (a threshold): never.
    """
    code = enc.code
    if isinstance(code, LatencyCode):
        if code.t_max - code.t_min <= 1:
            bad = render("np.zeros(parts.shape, bool)")
        elif code.rounding in ("floor", "dither"):
            bad = render("parts > $hi", hi=lit(float(code.x_max)))
        else:
            edge = code.t_min - 0.5
            bound = float(code.value_of(np.array(edge)))
            op = ">=" if np.rint(edge) < code.t_min else ">"
            bad = render("parts $op $bound", op=_code_op(op), bound=lit(bound))
    else:
        rate = render("$r * (parts - $lo) / $span", r=lit(float(code.max_rate)),
                      lo=lit(float(code.x_min)), span=lit(float(code.x_max - code.x_min)))
        top = float(np.floor(n_steps * code.max_rate + code.phase))
        bad = render("np.floor($n * ($rate) + $ph) > $top", n=lit(int(n_steps)), rate=rate,
                     ph=lit(float(code.phase)), top=lit(top))
    bounds = f"[{code.x_min:.6g}, {code.x_max:.6g}]{PER_PART[enc.split]}"
    lines = [render("bad = $bad", bad=bad)]
    if N_PARTS[enc.split]:
        lines.append(render("bad = bad.any(axis=-1)"))
    lines.append(render("port = $port\nbounds = $bounds\n"
                        "_kernels.check_range(port, x, bad, framed, policy, bounds)",
                        port=lit(enc.port), bounds=lit(bounds)))
    return join(lines)


def _code_op(op: str) -> Code:
    """A comparison operator as code (one of two fixed texts)."""
    return render({">": ">", ">=": ">="}[op])


#: What each decoder kind reads from the step loop: first spikes, counts or membranes.
DECODER_INPUT = {"spike_time": "first", "spike_table": "first", "count": "count",
                 "spiked": "count", "membrane": "v"}


def decode_function(pkg: PackageBuilder, module: str, dec: Decoder, pop: Population) -> str:
    """Write the decoder of port ``dec``; return its function name."""
    fn = pkg.function(module, "decode_", dec.port)
    a = dict(scale=lit(dec.scale), offset=lit(dec.offset), missing=lit(dec.missing))
    if dec.kind == "spike_time":
        value = _gained(dec, render("$scale * ($t_ref - t) + $offset", t_ref=lit(dec.t_ref),
                                    **a))
        body = render("t = activity.astype(np.float64)\nvalue = $value\n"
                      "y = np.where(activity >= 0, value, $missing)", value=value, **a)
    elif dec.kind in ("count", "membrane"):
        body = render("y = $value", value=_gained(
            dec, render("$scale * activity.astype(np.float64) + $offset", **a)))
    elif dec.kind == "spiked":
        body = render("y = (activity > 0).astype(np.float64)")
    else:
        key = pkg.store(module, fn, 0, "table", np.asarray(dec.table, np.float64))
        body = render(
            "key = $key\ntable = _kernels.array(key, 0, \"table\")\nk = activity - $t_ref\n"
            "inside = (activity >= 0) & (k >= 0) & (k < table.size)\n"
            "entry = table[np.clip(k, 0, table.size - 1)]\nvalue = $scale * entry + $offset\n"
            "y = np.where(inside, $value, $missing)", key=lit(key),
            t_ref=lit(int(dec.t_ref)),
            value=render("value") if dec.gain_axis is None else render("value / gains"), **a)
    if dec.gain_axis is not None:
        body = join([_gains_prologue(pkg, module, fn, dec, pop), body])
    pkg.add(module, render(
        template("decode.tmpl"), fn=ident(fn), summary=render("kind $k", k=lit(dec.kind)),
        port=comment(dec.port), pop=comment(pop.id), body=indent(body), dims=lit(pop.dims),
        combine=lit(dec.combine)))
    return fn


def _gained(dec: Decoder, value: Code) -> Code:
    """``(value) / gains`` for a decoder with gains (the reference's order), else ``value``."""
    return value if dec.gain_axis is None else render("($v) / gains", v=value)


def _gains_prologue(pkg: PackageBuilder, module: str, fn: str, dec: Decoder,
                    pop: Population) -> Code:
    """Per-neuron ``gains`` (flat, memory order) and ``activity`` as ``(frames, neurons)``.

    The gains along ``dec.gain_axis`` are stored once and broadcast in the generated code,
    as :meth:`~compiler.snn.Decoder.neuron_gains` does (the same values, so the division
    is bit-identical to the reference's).
    """
    dec.neuron_gains(pop.shape)  # refuses gains that do not fit the population
    key = pkg.store(module, fn, 1, "gains", np.asarray(dec.gains, np.float64))
    view = tuple(len(dec.gains) if a == dec.gain_axis else 1 for a in pop.axes)
    return render("gains = _kernels.array($key, 1, \"gains\").reshape($view)\n"
                  "gains = np.broadcast_to(gains, $dims).ravel()\n"
                  "activity = activity.reshape(-1, gains.size)", key=lit(key), view=lit(view),
                  dims=lit(pop.dims))
