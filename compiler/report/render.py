"""The :class:`Report`: a JSON-able dict with Markdown and core-map renderings.

JSON schema (``schema: "radarsnn-report/1"``; see ``docs/report.md``)::

    chain, target, frame_rate_hz
    stages[]      node, motif, network, inputs, neurons, synapses, time_steps, repetitions,
                  multiplexed, steps_per_frame, cores, blocks, synapse_memory_bits, *_total,
                  spikes_bound, ...
    frame_io[]    name, source, shape, values, bits_per_value, bytes, memory_kB, bandwidth_Mbit_s
    boundaries[]  kind, from, to, node, shape, values_per_frame, bits_per_value, crossings,
                  bits_per_frame, kB_per_frame, Mbit_s
    cfar_ops[]    node, n_train, algorithm, add, cmp, total[, n_steps]
    latency       networks[] (network, time_steps, runs, latency_steps, step_s, latency_s);
                  total_steps, total_s, frame_period_s, fits, max_step_s, step_note
    energy        stages[] (node, network, basis, synaptic_events, neuron_updates, spikes,
                  synaptic_J, neuron_J, spike_J, energy_J, latency_s, dsp_cycles, dsp_J,
                  dsp_latency_s); dynamic_J, static_J, total_J, chips, dsp_J, dsp_latency_s,
                  dynamic_to_dsp, total_to_dsp, basis, constants[] (name, value, source), note
    cores[]       core, chip, stage (the first placed), stages (all, in placement order),
                  neurons, input_axons, output_axons, synapse_bits, utilisation
    traffic       host_input, inter_core, inter_chip, buffered (messages per frame), basis
    totals        inputs, neurons, synapses, synapses_stored, cores, chips, synapse_memory_bits
    chips[]       (multi-chip profiles only) chip, cores, neurons, synapses, synapse_bits, in, out
                  (inter-chip messages per frame), in_bit_s, out_bit_s, link_utilisation
    inter_chip    (multi-chip profiles only) chips, messages_per_frame, bit_s, message_bits,
                  bandwidth_bit_s, busiest_link_bit_s, link_time_s, hop_latency_s,
                  crossing_steps, added_latency_s, latency_with_inter_chip_s, fits, note
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["TOTALS_HEADERS", "Report", "energy_line", "latency_line", "totals_line"]

#: How the Markdown and the summaries name the totals whose keys alone would be ambiguous.
TOTALS_HEADERS = {"synapses": "synapse_instances", "synapses_stored": "synapses_stored"}

_STAGE_COLUMNS = ("node", "motif", "inputs", "neurons", "synapses", "time_steps", "repetitions",
                  "multiplexed", "steps_per_frame", "cores", "synapse_memory_bits",
                  "spikes_bound", "synaptic_events_bound")


def _fmt(v) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int | np.integer):
        return f"{int(v):,}".replace(",", " ")
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e15:
        return _fmt(int(v))
    if isinstance(v, float):
        return f"{v:,.4g}".replace(",", " ") if abs(v) < 1e6 else f"{v:.3e}"
    return str(v)


def totals_line(totals: dict) -> str:
    """The totals in one line, stored synapses and synapse instances each named.

    A stored synapse is one weight entry held in a core's memory; an instance is one
    connection of the network as wired (a shared matrix or a stencil kernel is stored
    once and wired many times; docs/report.md).

    Examples
    --------
    >>> print(totals_line({"inputs": 4, "neurons": 1064960, "synapses": 609157632,
    ...                    "synapses_stored": 1032408, "cores": 92, "chips": 1,
    ...                    "synapse_memory_bits": None}))
    neurons 1 064 960, synapses stored 1 032 408 (synapse instances 609 157 632), cores 92, chips 1
    """
    parts = [f"neurons {_fmt(totals.get('neurons'))}"]
    if "synapses_stored" in totals:
        parts.append(f"synapses stored {_fmt(totals['synapses_stored'])} "
                     f"(synapse instances {_fmt(totals.get('synapses'))})")
    elif "synapses" in totals:
        parts.append(f"synapse instances {_fmt(totals['synapses'])}")
    parts += [f"{k} {_fmt(totals[k])}" for k in ("cores", "chips") if totals.get(k) is not None]
    return ", ".join(parts)


def _table(rows: list[dict], cols: tuple[str, ...],
           headers: dict[str, str] | None = None) -> list[str]:
    # Not tabulate: a pipe table is these three lines once the cells are formatted (_fmt
    # does the numbers), and tabulate's "github" format pads every column, which would
    # change each stored report.md (artifacts are compared byte for byte) for a new core
    # dependency and no gain for a reader of the rendered Markdown.
    cols = tuple(c for c in cols if any(c in r for r in rows))
    names = [(headers or {}).get(c, c) for c in cols]
    out = ["| " + " | ".join(names) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(_fmt(r.get(c)) for c in cols) + " |" for r in rows]
    return out


def _accuracy_lines(acc: dict, selection: dict | None) -> list[str]:
    """The accuracy contract per stage, and the configurations the motif search tried."""
    held = "held-out" if acc["held_out"] else "calibration (not held-out)"
    lines = ["", f"## Accuracy on {acc['n_frames']} {held} frame(s): "
             f"{'holds' if acc['holds'] else 'FAILS'}", ""]
    if acc.get("note"):
        lines += [f"Note: {acc['note']}.", ""]
    rows = []
    for s in acc["stages"]:
        f = s["figures"]
        rows.append({"node": s["node"], "motif": s["motif"], "kind": s["kind"],
                     "error_dB_re_noise": f.get("error_db"), "lost": f.get("lost"),
                     "sensitivity": f.get("sensitivity"), "precision": f.get("precision"),
                     "objects_kept": f"{f['kept']}/{f['objects']}" if "kept" in f else None,
                     "extra_per_map": f.get("extra_per_map"), "clipped": s["clipped"],
                     "failures": "; ".join(s["failures"]) or "—"})
    lines += _table(rows, ("node", "motif", "kind", "error_dB_re_noise", "lost", "sensitivity",
                           "precision", "objects_kept", "extra_per_map", "clipped",
                           "failures"))
    if selection:
        lines += ["", "Configurations tried (`motifs=\"auto\"`):", ""]
        lines += _table([{"#": i, "config": ", ".join(f"{k}: {v}" for k, v in a["config"].items()),
                          "steps": a["steps"], "fits": a["fits"], "holds": a["holds"],
                          "chosen": i == selection.get("chosen"),
                          "failures": "; ".join(a["failures"]) or (a["error"] or "—")}
                         for i, a in enumerate(selection["attempts"])],
                        ("#", "config", "steps", "fits", "holds", "chosen", "failures"))
    return lines


def latency_line(latency: dict) -> str:
    """The real-time fit in seconds: latency per frame, frame period, whether it fits.

    ``latency`` is a report's ``latency`` entry (the module docstring's schema).

    Examples
    --------
    >>> print(latency_line({"total_steps": 263269, "total_s": 2.63269, "frame_period_s": 0.1,
    ...                     "fits": False, "max_step_s": 3.798e-07,
    ...                     "networks": [{"step_s": 1e-05}]}))  # doctest: +NORMALIZE_WHITESPACE
    latency 2.633 s per frame (263 269 steps x 1e-05 s) against a frame period of 0.1 s:
    does NOT fit (it would with steps of at most 3.798e-07 s)
    >>> print(latency_line({"total_steps": 100, "total_s": None, "frame_period_s": 0.1,
    ...                     "fits": None}))  # doctest: +NORMALIZE_WHITESPACE
    latency 100 steps per frame, frame period 0.1 s: the target gives no step duration,
    so no fit in seconds
    """
    steps, total_s = latency.get("total_steps"), latency.get("total_s")
    period = latency["frame_period_s"]
    if total_s is None:
        return (f"latency {_fmt(steps)} steps per frame, frame period {_fmt(period)} s: the "
                "target gives no step duration, so no fit in seconds")
    step_s = next((r["step_s"] for r in latency.get("networks", ()) if r.get("step_s")), None)
    per_step = f" x {step_s:g} s" if step_s else ""
    fit = "fits" if latency["fits"] else "does NOT fit"
    if not latency["fits"] and latency.get("max_step_s"):
        fit += f" (it would with steps of at most {latency['max_step_s']:.4g} s)"
    return (f"latency {total_s:.4g} s per frame ({_fmt(steps)} steps{per_step}) against a "
            f"frame period of {period:g} s: {fit}")


def _joules(v: float | None) -> str:
    """An energy with an SI prefix, 4 significant digits (``None``: not published)."""
    if v is None:
        return "not published"
    for scale, unit in ((1.0, "J"), (1e-3, "mJ"), (1e-6, "µJ"), (1e-9, "nJ")):
        if abs(v) >= scale:
            return f"{v / scale:.4g} {unit}"
    return f"{v / 1e-12:.4g} pJ"


def energy_line(energy: dict, target: str) -> str:
    """One line: the chip's energy per frame on ``target`` and the DSP's beside it.

    ``energy`` is a report's ``energy`` entry (the module docstring's schema).

    Examples
    --------
    >>> print(energy_line({"total_J": 1.06, "dynamic_J": 0.04, "static_J": 1.02,
    ...                    "dsp_J": 0.0049, "total_to_dsp": 216.3, "basis": "bound"},
    ...                   "loihi"))  # doctest: +NORMALIZE_WHITESPACE
    energy ≈ 1.06 J/frame on loihi (dynamic 40 mJ + static 1.02 J; bound counts);
    conventional DSP (C674x) ≈ 4.9 mJ/frame, chip/DSP = 216
    >>> print(energy_line({"total_J": None, "dynamic_J": None, "static_J": None,
    ...                    "dsp_J": 0.0049, "total_to_dsp": None, "basis": "bound"},
    ...                   "loihi2"))  # doctest: +NORMALIZE_WHITESPACE
    energy per frame on loihi2: not published (no per-operation figures);
    conventional DSP (C674x) ≈ 4.9 mJ/frame
    """
    dsp = f"conventional DSP (C674x) ≈ {_joules(energy['dsp_J'])}/frame"
    if energy["dynamic_J"] is None:
        return (f"energy per frame on {target}: not published (no per-operation figures); "
                + dsp)
    if energy["total_J"] is None:
        chip = f"dynamic {_joules(energy['dynamic_J'])}/frame on {target} (static not known"
    else:
        chip = (f"{_joules(energy['total_J'])}/frame on {target} (dynamic "
                f"{_joules(energy['dynamic_J'])} + static {_joules(energy['static_J'])}")
    ratio = energy.get("total_to_dsp") or energy.get("dynamic_to_dsp")
    return (f"energy ≈ {chip}; {energy['basis']} counts); {dsp}"
            + (f", chip/DSP = {ratio:.3g}" if ratio else ""))


def _energy_lines(e: dict, target: str) -> list[str]:
    """The report's section on energy and latency per frame, with every constant's source."""
    lines = ["", "## Energy and latency per frame", "", energy_line(e, target) + ".", ""]
    published = any(c["name"].startswith(f"{target}.") for c in e["constants"])
    rows = [{**r, **{k: r[k] if r[k] is not None or not published else "not published"
                     for k in ("synaptic_J", "neuron_J", "spike_J", "energy_J")}}
            for r in e["stages"]]
    lines += _table(rows, ("node", "basis", "synaptic_events", "neuron_updates", "spikes",
                           "energy_J", "latency_s", "dsp_cycles", "dsp_J", "dsp_latency_s"))
    lines += ["", f"Chip: dynamic {_joules(e['dynamic_J'])} + static "
              f"{_joules(e['static_J'])} ({e['chips']} chip(s) x latency) = "
              f"{_joules(e['total_J'])} per frame; DSP: {_joules(e['dsp_J'])} in "
              f"{_fmt(e['dsp_latency_s'])} s per frame. Note: {e['note']}.", "",
              "Constants (values in SI units: J, W, Hz, cycles; – = not published, or a formula "
              "given in its source):", ""]
    lines += _table(e["constants"], ("name", "value", "source"))
    return lines


@dataclass
class Report:
    """A resource report; ``data`` follows the schema in the module docstring."""

    data: dict

    def to_json(self, indent: int = 2) -> str:
        """The report as JSON text."""
        return json.dumps(self.data, indent=indent, default=_json_default)

    def latency_line(self) -> str:
        """One line: latency per frame and frame period in seconds, and the fit."""
        return latency_line(self.data["latency"])

    def energy_line(self) -> str | None:
        """One line: energy per frame on the chip and on the DSP (None: no energy entry)."""
        e = self.data.get("energy")
        return None if e is None else energy_line(e, self.data["target"])

    def to_markdown(self) -> str:
        """The report as Markdown tables."""
        d = self.data
        lines = [f"# Resource report: {d['chain']} on {d['target']}", ""]
        lines += ["## Stages (per repetition)", ""]
        if any(r.get("multiplexed") for r in d["stages"]):
            lines += ["Multiplexed stages are time-multiplexed: one instance is placed (its "
                      "`cores` and `synapse_memory_bits`) and run `repetitions` times per "
                      "frame (`steps_per_frame` = repetitions × time_steps).", ""]
        lines += _table(d["stages"], _STAGE_COLUMNS + ("spikes_measured",
                                                       "synaptic_events_measured"))
        lines += ["", f"## Frame I/O at {d['frame_rate_hz']:g} frames/s", ""]
        if d["frame_io"]:
            lines += _table(d["frame_io"], ("name", "source", "shape", "bits_per_value",
                                            "memory_kB", "bandwidth_Mbit_s"))
        else:  # an empty pipe table renders as a broken row
            lines += ["None: the chain has no `adc_input` cube and no range-Doppler or "
                      "range-angle map."]
        if d.get("boundaries"):
            lines += ["", "## Segment boundaries (host ↔ spiking, per frame)", ""]
            lines += _table(d["boundaries"], ("kind", "from", "to", "node", "values_per_frame",
                                              "bits_per_value", "kB_per_frame", "Mbit_s"))
            lines += ["", "Total host ↔ chip traffic: "
                      f"{_fmt(sum(r['Mbit_s'] for r in d['boundaries']))} Mbit/s."]
        if d["cfar_ops"]:
            lines += ["", "## Operations per cell under test (Table 1)", ""]
            lines += _table(d["cfar_ops"], ("node", "algorithm", "add", "cmp", "total"))
        lat = d["latency"]
        lines += ["", "## Latency", ""]
        lines += _table(lat["networks"], ("network", "time_steps", "runs", "latency_steps",
                                          "step_s", "latency_s"))
        lines += ["", f"Total {_fmt(lat.get('total_steps'))} steps = {_fmt(lat['total_s'])} s "
                  f"per frame against a frame period of {_fmt(lat['frame_period_s'])} s: "
                  f"fits = {_fmt(lat['fits'])}"
                  + (f" (it would fit with steps of at most {_fmt(lat['max_step_s'])} s)"
                     if lat.get("max_step_s") else "") + "."]
        if lat.get("step_note"):
            lines += ["", f"Note: {lat['step_note']}."]
        if d.get("energy"):
            lines += _energy_lines(d["energy"], d["target"])
        if d.get("accuracy"):
            lines += _accuracy_lines(d["accuracy"], d.get("motif_selection"))
        if d.get("formats"):
            lines += ["", "## Number formats and dynamic-range mechanisms", ""]
            lines += _table(d["formats"], ("node", "item", "mechanism", "detail", "cost"))
        lines += ["", "## Totals", ""]
        lines += [totals_line(d["totals"]) + ".", ""]
        lines += _table([d["totals"]], tuple(d["totals"]), TOTALS_HEADERS)
        lines += ["", f"## Spike traffic per frame ({d['traffic'].get('basis', '')})", ""]
        lines += _table([d["traffic"]], ("host_input", "inter_core", "inter_chip", "buffered"))
        if d["cores"]:
            util = np.array([c["utilisation"] for c in d["cores"]])
            lines += ["", f"## Cores: {len(d['cores'])} used", "",
                      "Utilisation (mean / max) per budget: " + ", ".join(
                          f"{k} {m:.1%} / {x:.1%}" for k, m, x in
                          zip(d["budgets"], util.mean(axis=0), util.max(axis=0), strict=True))]
        if d.get("chips"):
            lines += _chip_lines(d)
        return "\n".join(lines) + "\n"

    def core_map_png(self) -> bytes:
        """The cores coloured by stage, filled to their utilisation: a PNG file's bytes.

        See :mod:`compiler.report.core_map` (every stage on a core is drawn, a shared
        core split between its stages; the legend's colours are the patches').
        """
        import matplotlib.pyplot as plt

        from compiler.report.core_map import core_map_figure  # matplotlib: only when drawing

        fig = core_map_figure(self.data)
        png = io.BytesIO()
        fig.savefig(png, dpi=100, bbox_inches="tight", format="png")
        plt.close(fig)
        return png.getvalue()

    def save_core_map(self, path: str | Path) -> Path:
        """Write :meth:`core_map_png` to ``path``; return it (``radarsnn report --core-map``
        and the demo write it atomically instead)."""
        path = Path(path)
        path.write_bytes(self.core_map_png())
        return path


def _chip_lines(d: dict) -> list[str]:
    x = d["inter_chip"]
    lines = ["", f"## Chips: {x['chips']} used (inter-chip spike traffic per frame)", ""]
    lines += _table(d["chips"], ("chip", "cores", "neurons", "synapses", "in", "out", "in_bit_s",
                                 "out_bit_s", "link_utilisation"))
    lines += ["", f"Inter-chip: {_fmt(x['messages_per_frame'])} messages per frame = "
              f"{_fmt(x['bit_s'])} bit/s at {_fmt(x['message_bits'])} bits per message; busiest "
              f"chip link {_fmt(x['busiest_link_bit_s'])} bit/s of {_fmt(x['bandwidth_bit_s'])}. "
              f"Added latency ≤ {_fmt(x['crossing_steps'])} crossing steps × "
              f"{_fmt(x['hop_latency_s'])} s + {_fmt(x['link_time_s'])} s on the busiest link = "
              f"{_fmt(x['added_latency_s'])} s per frame"
              + (f"; with it the frame takes {_fmt(x['latency_with_inter_chip_s'])} s, fits = "
                 f"{_fmt(x['fits'])}" if "fits" in x else "") + ".", "", f"Note: {x['note']}."]
    return lines


def _json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON-serialisable: {type(o).__name__}")
