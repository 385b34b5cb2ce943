"""The resource report of a compiled program: stages, frame I/O, CFAR op counts, cores.

:func:`build_report` gathers :mod:`~compiler.report.stages` (Table 3 bottom),
:mod:`~compiler.report.frame_io` (Table 3 top), :mod:`~compiler.report.opcounts`
(Table 1), the host/spiking :mod:`~compiler.report.boundaries`, latency, the
:mod:`~compiler.report.energy` per frame (beside the :mod:`~compiler.report.conventional`
DSP) and the placement into a :class:`~compiler.report.render.Report` (``to_json``, ``to_markdown``,
``save_core_map``).  See ``docs/report.md``.
"""

from __future__ import annotations

from collections.abc import Sequence

from compiler.hardware import BUDGETS
from compiler.report.boundaries import boundary_rows
from compiler.report.chips import chip_rows
from compiler.report.conventional import conventional_rows
from compiler.report.energy import energy_section
from compiler.report.formats import format_rows
from compiler.report.frame_io import frame_io
from compiler.report.opcounts import graph_cfar_op_counts
from compiler.report.render import Report
from compiler.report.stages import measured_rows, stage_rows

__all__ = ["Report", "add_measured_activity", "build_report", "network_runs"]

SCHEMA = "radarsnn-report/1"


def network_runs(rows: list[dict]) -> int:
    r"""Runs of a network's time window per frame: :math:`\sum_{s \in M} R_s + [S \ne M]`.

    ``rows`` are the network's stage rows; :math:`M` its multiplexed stages, each
    run :math:`R_s` times one after the other, and the spatial stages (if any) run
    once, all of them in one window (a network without stages runs once).

    Examples
    --------
    >>> network_runs([{"multiplexed": True, "repetitions": 256},
    ...               {"multiplexed": False, "repetitions": 1}])
    257
    """
    mux = sum(r["repetitions"] for r in rows if r.get("multiplexed"))
    return mux + int(not rows or any(not r.get("multiplexed") for r in rows))


def _step_note(profile) -> str:
    if profile.time_step_s is None:
        return f"{profile.name} gives no time-step duration: no latency in seconds"
    return (f"time_step_s = {profile.time_step_s:g} s is an assumption of the {profile.name} "
            "profile, not a published figure (a real step's duration depends on the activity)")


def build_report(program, *, sim_results: Sequence | None = None,
                 frame_rate_hz: float | None = None, real_bits: int = 16,
                 n_angle_bins: int | None = None) -> Report:
    """The resource report of ``program`` (a :class:`~compiler.program.CompiledProgram`).

    Parameters
    ----------
    program : CompiledProgram
        Uses ``graph``, ``networks``, ``target`` and the ``split`` / ``placement``
        records when present (the passes ``split`` and ``place`` produce them).
    sim_results : sequence of SimResult, optional
        One per network, for measured spikes and synaptic events.
    frame_rate_hz : float, optional
        Frames per second (default 10; the ``report`` pass gives the compile option
        ``frame_rate_hz``).
    real_bits : int
        Bits per real value of the frame I/O (complex: twice).
    n_angle_bins : int, optional
        Angle bins of an RA map the chain does not compute (CARRADA's: 256), for the frame
        I/O of a chain whose angle stage runs elsewhere; None (the default): an RA map row
        only when the chain computes one.

    Returns
    -------
    Report

    Examples
    --------
    >>> from pathlib import Path
    >>> from compiler.program import CompiledProgram
    >>> from ir import Graph
    >>> g = Graph.from_yaml(Path("examples/chains/carrada_rd_oscfar.yaml"))
    >>> rep = build_report(CompiledProgram(graph=g))
    >>> [(r["name"], round(r["memory_kB"], 1)) for r in rep.data["frame_io"]]
    [('raw_cube', 262.1), ('rd_map', 32.8)]
    >>> rep = build_report(CompiledProgram(graph=g), n_angle_bins=256)  # CARRADA's RA map
    >>> [(r["name"], round(r["memory_kB"], 1)) for r in rep.data["frame_io"]][-1]
    ('ra_map', 131.1)
    """
    profile = program.sized_for
    rate = float(frame_rate_hz or 10.0)  # the ReportPass gives the option frame_rate_hz
    networks = program.networks
    splits = program.records.splits or [None] * len(networks)
    placement = program.records.placement
    sims = list(sim_results) if sim_results is not None else [None] * len(networks)
    stages = []
    for k, (net, sp, sim) in enumerate(zip(networks, splits, sims, strict=True)):
        stages += stage_rows(net, split=sp, placement=placement, net_index=k,
                             bits_per_synapse=profile.bits_per_synapse, sim=sim)
    steps = {}
    for net in networks:
        for p in net.populations:
            if "node" in p.origin:
                steps[p.origin["node"]] = net.n_steps
    step_s = profile.time_step_s
    lat_rows = []
    for n in networks:
        runs = network_runs([r for r in stages if r["network"] == n.name])
        lat_rows.append({"network": n.name, "time_steps": n.n_steps, "runs": runs,
                         "latency_steps": runs * n.n_steps, "step_s": step_s,
                         "latency_s": runs * n.n_steps * step_s if step_s else None})
    total_steps = sum(r["latency_steps"] for r in lat_rows)
    total_s = total_steps * step_s if step_s else None
    cores = []
    if placement is not None:
        stage_of = {(k, p.id): p.origin.get("node", p.id)
                    for k, n in enumerate(networks) for p in n.populations}
        on_core: dict[int, list[str]] = {}  # every stage placed on a core, in placement order
        for (k, pid, _), c in zip(placement.items, placement.core, strict=True):
            placed = on_core.setdefault(int(c), [])
            if stage_of[(k, pid)] not in placed:
                placed.append(stage_of[(k, pid)])
        for c in range(placement.n_cores):
            cores.append({"core": c, "chip": int(c // profile.cores_per_chip)
                          if profile.cores_per_chip else 0,
                          "stage": on_core.get(c, ["?"])[0], "stages": on_core.get(c, ["?"]),
                          **dict(zip(BUDGETS, placement.usage[c].tolist(), strict=True)),
                          "utilisation": placement.utilisation[c].round(6).tolist()})
    totals = {
        "inputs": sum(r["inputs_total"] for r in stages),
        "neurons": sum(r["neurons_total"] for r in stages),
        "synapses": sum(r["synapses_total"] for r in stages),
        "synapses_stored": sum(r["synapses_stored"] for r in stages),
        "cores": placement.n_cores if placement is not None else None,
        "chips": placement.n_chips if placement is not None else None,
        "synapse_memory_bits": sum(r.get("synapse_memory_bits", 0) for r in stages)
        if splits[0:1] != [None] else None,
    }
    data = {
        "schema": SCHEMA, "chain": program.graph.name, "target": profile.name,
        "frame_rate_hz": rate, "budgets": list(BUDGETS),
        "cores_per_chip": profile.cores_per_chip, "stages": stages,
        "frame_io": frame_io(program.graph, frame_rate_hz=rate, real_bits=real_bits,
                             n_angle_bins=n_angle_bins),
        "boundaries": boundary_rows(program, frame_rate_hz=rate, real_bits=real_bits),
        "cfar_ops": graph_cfar_op_counts(program.graph, steps),
        "latency": {"networks": lat_rows, "total_steps": total_steps, "total_s": total_s,
                    "frame_period_s": 1.0 / rate,
                    "fits": None if total_s is None else total_s <= 1.0 / rate,
                    "max_step_s": 1.0 / rate / total_steps if total_steps else None,
                    "step_note": _step_note(profile)},
        "cores": cores,
        "traffic": dict(placement.traffic) if placement is not None else {},
        "totals": totals,
        "formats": format_rows(program),
    }
    data["energy"] = _energy(data, program, profile)
    if placement is not None and getattr(placement, "chip_messages", None) is not None:
        # a multi-chip board: the per-chip table and the inter-chip traffic (single chip: none)
        data["chips"], data["inter_chip"] = chip_rows(placement, profile, rate, lat_rows)
        added = data["inter_chip"]["added_latency_s"]
        if total_s is not None and added is not None:
            data["inter_chip"]["latency_with_inter_chip_s"] = total_s + added
            data["inter_chip"]["fits"] = total_s + added <= 1.0 / rate
    return Report(data)


def _energy(data: dict, program, profile) -> dict:
    placement = program.records.placement
    return energy_section(
        data["stages"], profile, latency_s=data["latency"]["total_s"],
        n_chips=placement.n_chips if placement is not None else 1,
        conventional=conventional_rows(program.graph, [r["node"] for r in data["stages"]]))


def add_measured_activity(report: Report, program, sim_results: Sequence) -> None:
    """Fill ``report``'s measured spikes and synaptic events, and its energy, from simulations.

    For a report built before the program was simulated (the measured compile runs the
    held-back frames after the ``report`` pass): each stage row gains
    ``spikes_measured`` and ``synaptic_events_measured`` (means per frame) and the
    ``energy`` entry is recomputed on them (``basis: measured``).

    Parameters
    ----------
    report : Report
        ``program.records.report``.
    program : CompiledProgram
        The program simulated.
    sim_results : sequence of SimResult
        One per network (spiking segment), in order; another count changes nothing.
    """
    networks = program.networks
    if len(sim_results) != len(networks) or not networks:
        return
    for net, sim in zip(networks, sim_results, strict=True):
        fields = measured_rows(net, sim)
        for row in report.data["stages"]:
            if row["network"] == net.name and row["node"] in fields:
                row.update(fields[row["node"]])
    report.data["energy"] = _energy(report.data, program, program.sized_for)
