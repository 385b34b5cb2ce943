"""The report's number-format section: what each dynamic-range mechanism chose and costs.

One row per mechanism instance of a compiled program, from the networks themselves and the
quantize pass's record (``records["quantize"]``):

* ``weight_format`` — per projection: its exponent, mantissa width and whether it is exact;
* ``split_synapses`` — a projection whose whole weights needed further terms (the OS-CFAR's
  odd clipped-edge ranks): the extra synapse instances they wire;
* ``neuron_scales`` — per-neuron threshold/bias scales (the S-FT's per-neuron gains): the
  neurons that carry one, the largest scale, and the per-neuron parameter memory (one
  bias exponent and one initial membrane per neuron, ``3 + state_bits`` bits — assumed);
* ``weight_rounding`` — per time-coded layer: its weight width and rounding rule;
* ``graded_readout`` — a layer that sends its membrane as one graded spike: the payload
  width and the payload traffic per frame (no charging stage);
* ``charging_guard`` — a host-decoded layer's guard above the calibrated full scale: its
  ratio and the charging steps it takes from the window;
* ``input_dither`` — an encoder whose rounding is dithered: the extra rounding noise;
* ``resonator`` — a resonator DFT layer (:mod:`compiler.lowering.resonator`): its stream
  bits, coefficient format and drift bound, read-out code and steps per chirp; the cost is
  its state memory (two ``state_bits`` words per bin);
* ``static_split`` — the part repeating over chirps computed on the host: the host
  multiply-adds per frame it adds (chirp mean, its range DFT, the rank-one Doppler product
  and the sum).

Examples
--------
>>> from compiler.program import CompiledProgram
>>> from ir import Graph
>>> format_rows(CompiledProgram(graph=Graph.from_dict({"name": "e", "nodes": []})))
[]
"""

from __future__ import annotations

__all__ = ["format_rows"]


def _instances(net, proj) -> int:
    pops = net.population
    return proj.n_synapse_instances(pops[proj.source], pops[proj.target])


def format_rows(program) -> list[dict]:
    """Rows ``{node, item, mechanism, detail, cost}`` for the report (see the module doc)."""
    profile = program.sized_for
    records = program.records.quantization
    rows: list[dict] = []
    for k, net in enumerate(program.networks):
        rec = records[k].projections if k < len(records) else {}
        for proj in net.projections:
            node = proj.origin.get("node", proj.id)
            r = rec.get(proj.id)
            if r is not None:
                rows.append({"node": node, "item": proj.id, "mechanism": "weight_format",
                             "detail": f"{r['mantissa_bits']}-bit mantissa x 2^{r['exponent']}"
                                       + (", exact" if r.get("exact") else
                                          f", max rel. error {r['max_rel_error']:.2g}"),
                             "cost": ""})
            if "__x" in proj.id:
                rows.append({"node": node, "item": proj.id, "mechanism": "split_synapses",
                             "detail": "a further term of whole weights beyond one exponent",
                             "cost": f"{_instances(net, proj):,} synapses"})
        bits = 3 + profile.number_format.state_width
        for pop in net.populations:
            par = pop.params
            if par.scale_axis is not None:
                rows.append({"node": pop.origin.get("node", pop.id), "item": pop.id,
                             "mechanism": "neuron_scales",
                             "detail": f"per-{par.scale_axis} threshold/bias scale up to "
                                       f"{max(par.scales):g}",
                             "cost": f"{pop.size:,} neurons x {bits} bits = "
                                     f"{pop.size * bits / 8192:.1f} kB"})
        for node, ch in (net.meta.get("charging") or {}).items():
            rule = ",".join(sorted(set(ch.get("rounding") or ["nearest"])))
            rows.append({"node": node, "item": node, "mechanism": "weight_rounding",
                         "detail": f"{ch.get('weight_bits')}-bit levels, {rule}, "
                                   f"{ch.get('kind')} charging", "cost": ""})
        for node, ch in (net.meta.get("charging") or {}).items():
            guard = ch.get("guard") or {}
            if ch.get("kind") == "graded":
                pop = net.population[f"{node}/out"] if f"{node}/out" in net.population else None
                size = pop.size if pop is not None else 0
                rows.append({"node": node, "item": node, "mechanism": "graded_readout",
                             "detail": f"membrane sent as a {ch['payload_bits']}-bit payload, "
                                       f"guard {guard.get('ratio', 1):g}x",
                             "cost": f"{size:,} payloads x {ch['payload_bits']} bits = "
                                     f"{size * ch['payload_bits'] / 8192:.1f} kB per frame"})
            if guard.get("steps"):
                rows.append({"node": node, "item": node, "mechanism": "charging_guard",
                             "detail": f"values up to {guard['ratio']:g}x the calibrated full "
                                       "scale coded, not clipped",
                             "cost": f"{guard['steps']} of {ch['n_steps']} charging steps"})
        state = profile.number_format.state_bits or 32  # float state: a float32
        for node, r in (net.meta.get("resonator") or {}).items():
            pop = net.population.get(f"{node}/out")
            n_res = pop.size // 4 if pop is not None else 0
            coef = f"{r['coef_bits']}-bit" if r["coef_bits"] else "float"
            rows.append({"node": node, "item": node, "mechanism": "resonator",
                         "detail": f"{r['stream_bits']}-bit stream, {coef} coefficients"
                                   f"{_renorm(r)}, drift bound {r['bound']:.3g} over "
                                   f"{r['input_steps']} steps, "
                                   f"{r['readout']} read-out: {r['input_steps']} + "
                                   f"{r['readout_steps']} steps per chirp",
                         "cost": f"{n_res:,} resonators x 2 x {state} bits "
                                 f"= {n_res * 2 * state / 8192:.1f} kB"})
        for enc in net.encoders:
            if getattr(enc.code, "rounding", None) == "dither":
                rows.append({"node": enc.node or enc.port, "item": enc.population,
                             "mechanism": "input_dither",
                             "detail": "rounding error white over the chirps (no repeated error)",
                             "cost": "rounding noise x2 (s^2/6 instead of s^2/12)"})
    rows += _split_rows(program)
    return rows


def _split_rows(program) -> list[dict]:
    types = program.graph.infer_types()
    rows = []
    for rec in program.records.static_splits:
        mean, *stages, static = rec["static"]
        adc = types[rec["input"]]
        macs = adc.size + types[rec["moving_input"]].size  # the chirp mean and x - mean
        for node in stages:  # the range stages on the mean (one chirp): n_in per output
            op, src = program.graph.op(node), program.graph.inputs_of(node)[0]
            macs += types[node].size * (types[src].axes[op.axis] if hasattr(op, "axis") else 1)
        macs += 2 * types[rec["add"]].size  # the rank-one product and the sum
        rows.append({"node": rec["add"], "item": ", ".join(rec["static"]),
                     "mechanism": "static_split",
                     "detail": f"the part of {rec['input']!r} repeating over {rec['axis']!r} "
                               "computed exactly on the host",
                     "cost": f"{macs:,} host multiply-adds per frame"})
    return rows


def _renorm(r: dict) -> str:
    """``", renormalised every M steps"`` where a layer renormalises (older records: none)."""
    m = r.get("renorm_steps") or 0
    return f", renormalised every {m} steps" if m else ""
