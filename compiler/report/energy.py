r"""What one frame costs on the chip: energy and latency per stage from per-operation figures.

For a stage with :math:`S` synaptic events, :math:`N` neurons updated for :math:`T`
steps and :math:`K` spikes per frame, on a chip whose profile gives the energy of a
synaptic event :math:`E_\mathrm{syn}`, of a neuron update :math:`E_\mathrm{neu}` and of a
spike :math:`E_\mathrm{spk}` (:class:`~compiler.hardware.figures.EnergyFigures`):

.. math:: E = S\,E_\mathrm{syn} + N T\,E_\mathrm{neu} + K\,E_\mathrm{spk},
          \qquad t = T_\mathrm{frame}\,\Delta t

with :math:`T_\mathrm{frame}` the stage's steps per frame (its repetitions times
:math:`T` when time-multiplexed) and :math:`\Delta t` the profile's ``time_step_s``.
:math:`S` and :math:`K` are the measured means per frame when the program was simulated
(``basis: measured``), else the bounds of :mod:`compiler.hardware.activity` (``bound``:
every neuron spiking as often as its code allows, so an upper bound). The chip's leakage
adds :math:`P_\mathrm{static} \cdot n_\mathrm{chips} \cdot t_\mathrm{frame}` for the whole
frame. A figure the profile leaves ``null`` makes the energy "not published", never 0.
Beside it, the same nodes on a radar DSP (:mod:`compiler.report.conventional`).

Each neuron is counted updated once per step of its own stage's runs (:math:`N T`; a
time-multiplexed stage's :math:`R` instances :math:`R` times the instance's); a chip that
also updates the neurons of a stage while another stage's instances run spends more.

Examples
--------
>>> from compiler.hardware.figures import EnergyFigures, Figure
>>> e = EnergyFigures(synaptic_op_j=Figure(value=2e-11, source="a"),
...                   neuron_update_j=Figure(value=1e-10, source="b"),
...                   spike_j=Figure(value=1e-12, source="c"))
>>> row = {"node": "f", "network": "n", "neurons_total": 4, "time_steps": 10,
...        "steps_per_frame": 10, "spikes_bound": 40.0, "synaptic_events_bound": 160.0}
>>> s = stage_energy(row, e, 1e-5)  # 160 x 20 pJ + 4 x 10 x 100 pJ + 40 x 1 pJ
>>> round(s["energy_J"] * 1e12, 6), s["latency_s"], s["basis"]
(7240.0, 0.0001, 'bound')
>>> stage_energy(row, None, 1e-5)["energy_J"] is None
True
"""

from __future__ import annotations

from collections.abc import Sequence

from compiler.hardware.figures import EnergyFigures
from compiler.report.conventional import DSP

__all__ = ["energy_section", "stage_energy"]

_TERMS = (("synaptic_events", "synaptic_op_j", "synaptic_J"),
          ("neuron_updates", "neuron_update_j", "neuron_J"),
          ("spikes", "spike_j", "spike_J"))


def _value(energy: EnergyFigures | None, name: str) -> float | None:
    fig = getattr(energy, name, None) if energy is not None else None
    return None if fig is None else fig.value


def stage_energy(row: dict, energy: EnergyFigures | None, step_s: float | None) -> dict:
    """Energy and latency per frame of one stage row (:mod:`compiler.report.stages`).

    Parameters
    ----------
    row : dict
        A stage row: ``neurons_total``, ``time_steps``, ``steps_per_frame`` and the
        ``spikes`` / ``synaptic_events`` bounds (and measured means when simulated).
    energy : EnergyFigures or None
        The profile's constants (``None``: none given).
    step_s : float or None
        The profile's ``time_step_s``.

    Returns
    -------
    dict
        ``node``, ``network``, ``basis``, the counts, each term in J (``None`` where its
        figure is not published), ``energy_J`` (their sum, or ``None``) and ``latency_s``.
    """
    measured = "spikes_measured" in row
    counts = {"synaptic_events": row["synaptic_events_measured" if measured
                                     else "synaptic_events_bound"],
              "neuron_updates": row["neurons_total"] * row["time_steps"],
              "spikes": row["spikes_measured" if measured else "spikes_bound"]}
    out = {"node": row["node"], "network": row["network"],
           "basis": "measured" if measured else "bound", **counts}
    for count, figure, term in _TERMS:
        e = _value(energy, figure)
        out[term] = None if e is None else counts[count] * e
    parts = [out[term] for _, _, term in _TERMS]
    out["energy_J"] = None if None in parts else sum(parts)
    out["latency_s"] = row["steps_per_frame"] * step_s if step_s else None
    return out


def energy_section(stages: Sequence[dict], profile, *, latency_s: float | None,
                   n_chips: int, conventional: Sequence[dict]) -> dict:
    """The report's ``energy`` entry: per stage, totals, the DSP beside them, the constants.

    Parameters
    ----------
    stages : sequence of dict
        The report's stage rows.
    profile : HardwareProfile
        The target (``energy``, ``time_step_s``).
    latency_s : float or None
        The frame's latency (the report's ``latency.total_s``), for the static energy.
    n_chips : int
        Chips the program uses (the static power is per chip).
    conventional : sequence of dict
        :func:`compiler.report.conventional.conventional_rows` of the same nodes.

    Returns
    -------
    dict
        ``stages`` (chip and DSP figures per stage), ``dynamic_J``, ``static_J``,
        ``total_J``, ``chips``, ``dsp_J``, ``dsp_latency_s``, ``dynamic_to_dsp`` and
        ``total_to_dsp`` (chip energy over the DSP's), ``basis``,
        ``constants`` (name, value, source of every figure used) and ``note``.
    """
    dsp = {r["node"]: r for r in conventional}
    rows = []
    for row in stages:
        s = stage_energy(row, profile.energy, profile.time_step_s)
        d = dsp.get(row["node"], {})
        s.update({"dsp_cycles": d.get("cycles"), "dsp_J": d.get("energy_J"),
                  "dsp_latency_s": d.get("latency_s")})
        rows.append(s)
    dynamic = _sum(r["energy_J"] for r in rows)
    power = _value(profile.energy, "static_power_w")
    static = None if power is None or latency_s is None else power * n_chips * latency_s
    total = None if dynamic is None or static is None else dynamic + static
    dsp_j = _sum(r["dsp_J"] for r in rows)
    constants = [{"name": f"{profile.name}.{k}", "value": f.value, "source": f.source}
                 for k, f in (profile.energy or EnergyFigures()) if f is not None]
    constants += [{"name": f"dsp.{k}", "value": f.value, "source": f.source}
                  for k, f in DSP.items()]
    bases = sorted({r["basis"] for r in rows})
    return {"stages": rows, "dynamic_J": dynamic, "static_J": static, "total_J": total,
            "chips": n_chips, "dsp_J": dsp_j,
            "dsp_latency_s": _sum(r["dsp_latency_s"] for r in rows),
            "dynamic_to_dsp": dynamic / dsp_j if dynamic is not None and dsp_j else None,
            "total_to_dsp": total / dsp_j if total is not None and dsp_j else None,
            "basis": "+".join(bases) or "none", "constants": constants,
            "note": _note(profile, bases, static is not None)}


def _sum(values) -> float | None:
    values = list(values)
    return None if not values or None in values else sum(values)


def _note(profile, bases: list[str], static: bool) -> str:
    if profile.energy is None:
        return f"{profile.name} gives no energy constants: no energy per frame"
    how = {"measured": "spike and synaptic-event counts measured on the checked frames",
           "bound": "spike and synaptic-event counts are upper bounds (every neuron as "
                    "active as its code allows), not measured"}
    parts = [how[b] for b in bases] or ["no spiking stage"]
    if static:
        parts.append(f"the static energy is the static power times the latency, which rests on "
                     f"time_step_s = {profile.time_step_s:g} s (an assumption of the profile)")
    return "; ".join(parts)
