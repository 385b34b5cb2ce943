r"""The step loop of a generated network module (``network_<k>.py``).

Per step ``t``, for each population in the reference plan's order: a source emits
its spikes (latency train slice or rate comparison); a neuron population sums,
where its input phase is on, the currents of its incoming projections (delay
class ``d`` reads the source's ring buffer at ``t - d``) in declaration order,
then takes its folded update; spikes are counted (and first spikes / per-neuron
counts kept where a decoder needs them).  This is ``backends.reference.step``
written out for one network.
"""

from __future__ import annotations

from backends.emit.numpy_network import (
    DECODER_INPUT,
    decode_function,
    deliver_function,
    encode_function,
    node_of,
    update_function,
)
from backends.emit.package import PackageBuilder
from backends.emit.render import Code, comment, ident, indent, join, lit, render, template
from backends.reference.neuron import StepParams
from backends.reference.plan import SimPlan
from compiler.snn.coding import N_PARTS, LatencyCode

__all__ = ["emit_network", "import_from"]


def _on_ranges(sp_: StepParams) -> list[tuple[int, int]]:
    """Merged ``[start, stop)`` ranges of steps where the input phase is on."""
    out: list[tuple[int, int]] = []
    for s in sp_.spans:
        if s.input_on:
            if out and out[-1][1] == s.start:
                out[-1] = (out[-1][0], s.stop)
            else:
                out.append((s.start, s.stop))
    return out


def _condition(ranges: list[tuple[int, int]], n_steps: int) -> Code | None:
    if ranges == [(0, n_steps)]:
        return None
    terms = [render("t < $b", b=lit(b)) if a == 0 else
             render("t >= $a", a=lit(a)) if b >= n_steps else
             render("$a <= t < $b", a=lit(a), b=lit(b)) for a, b in ranges]
    cond = terms[0]
    for term in terms[1:]:
        cond = render("$a or $b", a=cond, b=term)
    return render("if $c:", c=cond)


def emit_network(pkg: PackageBuilder, plan: SimPlan, integer: bool, header: Code) -> Code:
    """Write the stage functions of ``plan.network`` into ``pkg``; return its network module.

    Parameters
    ----------
    pkg : PackageBuilder
        The package being generated (stage functions and arrays are added to it).
    plan : SimPlan
        The reference plan of the network (``build_plan(network, arithmetic)``).
    integer : bool
        Integer (fixed-point) arithmetic.
    header : Code
        The header comment of every generated file.

    Returns
    -------
    Code
        The body of ``network_<index>.py`` (without the header).
    """
    net = plan.network
    pops = net.population
    var = {pid: i for i, pid in enumerate(plan.order)}
    stage_of = {pid: pkg.stage(node_of(p, p.id)) for pid, p in pops.items()}
    update = {pid: update_function(pkg, stage_of[pid], pops[pid], sp_) for pid, sp_ in
              plan.neurons.items()}
    deliver = {}
    for proj in net.projections:
        module = pkg.stage(node_of(proj, node_of(pops[proj.target], proj.target)))
        dl = plan.deliveries[proj.id]
        deliver[proj.id] = (module, deliver_function(pkg, module, proj, dl, pops, integer))
    var_q = {q.id: n for n, q in enumerate(net.projections)}
    need: dict[str, set[str]] = {pid: set() for pid in pops}
    decode = []
    for dec in net.decoders:
        need[dec.population].add(DECODER_INPUT[dec.kind])
        module = stage_of[dec.population]
        decode.append((dec, module, decode_function(pkg, module, dec, pops[dec.population])))
    encoders = {e.population: e for e in net.encoders}
    dtype = render("np.int64") if integer else render("np.float64")

    pro = []
    for j, enc in enumerate(net.encoders):
        pro.append(render("port = $port\nx_$j, f_$j = _kernels.port_value(inputs, port, $shape, "
                          "$cplx)\npolicy_$j = $policy",
                          j=lit(j), port=lit(enc.port), cplx=lit(enc.split in ("re_im",
                                                                               "re_im_signed")),
                          # a saturating code (its top a calibration quantile) clips by design
                          policy=render('"clip"') if enc.saturate else
                          render("_kernels.policy(out_of_range, port)"),
                          shape=lit(pops[enc.population].dims[:-1] if N_PARTS[enc.split] else
                                    pops[enc.population].dims)))
    for qid, (module, fn) in deliver.items():
        pro.append(render("deliver_$q = $m.$f", q=lit(var_q[qid]), m=ident(module), f=ident(fn)))
    pro.append(render("n_frames, framed = _kernels.batch([$f])", f=join(
        [render("f_$j", j=lit(j)) for j in range(len(net.encoders))], ", ")))
    loop = []
    for pid in plan.order:
        i, pop = lit(var[pid]), pops[pid]
        pro.append(render("# $i: population $p", i=i, p=comment(pid)))
        pro.append(render("ring_$i = [_kernels.EMPTY] * $h", i=i, h=lit(plan.history[pid])))
        pro.append(render("n_$i = 0", i=i))
        if "first" in need[pid]:
            pro.append(render("first_$i = np.full(n_frames * $s, -1, np.int64)", i=i,
                              s=lit(pop.size)))
        if "count" in need[pid]:
            pro.append(render("count_$i = np.zeros(n_frames * $s, np.int64)", i=i,
                              s=lit(pop.size)))
        loop.append(render("# $i: population $p", i=i, p=comment(pid)))
        if pid in encoders:
            enc = encoders[pid]
            j = lit(net.encoders.index(enc))
            fn = render("$m.$f", m=ident(stage_of[pid]), f=ident(
                encode_function(pkg, stage_of[pid], enc, pop, net.n_steps)))
            if isinstance(enc.code, LatencyCode):
                pro.append(render("encode = $fn\nflat_$i, bounds_$i = encode(x_$j, n_frames, "
                                  "framed, policy_$j)", i=i, fn=fn, j=j))
                loop.append(render("fired = flat_$i[bounds_$i[t]:bounds_$i[t + 1]]", i=i))
            else:
                pro.append(render("encode = $fn\nrates_$i = encode(x_$j, n_frames, framed, "
                                  "policy_$j)", i=i, fn=fn, j=j))
                ph = lit(enc.code.phase)
                loop.append(render("fired = np.flatnonzero(np.floor((t + 1) * rates_$i + $ph)\n"
                                   "                       > np.floor(t * rates_$i + $ph))", i=i,
                                   ph=ph))
        else:
            for name in ("u", "v"):
                pro.append(render("${n}_$i = np.zeros((n_frames, $s), $d)", n=ident(name), i=i,
                                  s=lit(pop.size), d=dtype))
            pro.append(render("fired_$i = np.zeros((n_frames, $s), bool)", i=i, s=lit(pop.size)))
            pro.append(render("update_$i = $m.$f", i=i, m=ident(stage_of[pid]),
                              f=ident(update[pid])))
            loop += _neuron_step(plan, pid, var, var_q)
        loop.append(render("ring_$i[t % $h] = fired", i=i, h=lit(plan.history[pid])))
        tail = [render("n_$i += fired.size", i=i)]
        if "count" in need[pid]:
            tail.append(render("count_$i[fired] += 1", i=i))
        if "first" in need[pid]:
            tail.append(render("new = fired[first_$i[fired] < 0]\nfirst_$i[new] = t", i=i))
        loop += [render("if fired.size:"), indent(join(tail))]
    epi = []
    for dec, module, fn in decode:
        i = lit(var[dec.population])
        src = {"first": "first_$i", "count": "count_$i", "v": "v_$i"}[DECODER_INPUT[dec.kind]]
        epi.append(render("decode = $m.$f\noutputs[$port] = decode(" + src + ", framed)",
                          port=lit(dec.port), m=ident(module), f=ident(fn), i=i))
    epi.append(render("spikes = {}"))
    for pid in pops:
        epi.append(render("spikes[$p] = n_$i", p=lit(pid), i=lit(var[pid])))
    modules = sorted({*stage_of.values(), *(m for m, _ in deliver.values())} | {"_kernels"})
    return render(template("network.py.tmpl"), network=comment(net.name),
                  imports=import_from(modules), n_steps=lit(net.n_steps),
                  ports=lit(tuple(e.port for e in net.encoders)),
                  prologue=indent(join(pro)), loop=indent(join(loop), 2),
                  epilogue=indent(join(epi)), header=header)


def _neuron_step(plan: SimPlan, pid: str, var: dict, var_q: dict) -> list[Code]:
    i = lit(var[pid])
    size = lit(plan.network.population[pid].size)
    adds = []
    for qid in plan.incoming[pid]:
        dl = plan.deliveries[qid]
        j, h = lit(var[dl.source]), lit(plan.history[dl.source])
        for k, d in enumerate(dl.delays):
            read = (render("ev = ring_$j[t % $h]", j=j, h=h) if d == 0 else
                    render("ev = ring_$j[(t - $d) % $h]", j=j, d=lit(d), h=h))
            add = render("if ev.size:\n    current = current + deliver_$q(ev, n_frames, $k)",
                         q=lit(var_q[qid]), k=lit(k))
            block = join([read, add])
            if d > 0:
                block = join([render("if t >= $d:", d=lit(d)), indent(block)])
            adds.append(block)
    lines = [render("current = 0")]
    cond = _condition(_on_ranges(plan.neurons[pid]), plan.network.n_steps)
    on = _on_ranges(plan.neurons[pid])
    if adds and on:
        adds.append(render("if not np.isscalar(current):\n    current = current.reshape("
                           "n_frames, $s)", s=size))
        body = join(adds)
        lines += [body] if cond is None else [cond, indent(body)]
    lines.append(render("spiked, u_$i, v_$i, fired_$i = update_$i(u_$i, v_$i, fired_$i, "
                        "current, t)", i=i))
    lines.append(render("fired = np.flatnonzero(spiked)"))
    return lines


def import_from(modules: list[str]) -> Code:
    """``from . import a, b`` as ruff's isort writes it (wrapped past 100 columns).

    Examples
    --------
    >>> str(import_from(["_kernels", "stage_a"]))
    'from . import _kernels, stage_a'
    """
    names = [ident(m) for m in modules]
    one = render("from . import $n", n=join(names, ", "))
    if len(str(one)) <= 100:
        return one
    return render("from . import (\n$n\n)", n=join([render("    $m,", m=m) for m in names]))
