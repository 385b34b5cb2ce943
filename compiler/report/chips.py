r"""The per-chip table and the inter-chip traffic of a placement on a multi-chip board.

Only for a profile of several chips (the placement carries ``chip_messages``); a
single-chip report has neither key.  Per chip: cores used, neurons, stored synapses
(``synapse_bits / bits_per_synapse``), and the spike messages per frame that leave it
(``out``) and reach it (``in``) from other chips — the ``inter_chip`` messages of the
traffic, by chip: one message per spike and destination core on another chip (a fabric
that multicasts once per chip would send fewer: this is an upper bound there).

At the frame rate :math:`f` and ``spike_message_bits`` :math:`b` a chip's link carries
:math:`\text{in}·b·f` and :math:`\text{out}·b·f` bit/s; ``link_utilisation`` is the larger
over ``inter_chip_bandwidth_bit_s``.  **Added latency** (an upper bound): every time step
of a network with inter-chip messages waits ``inter_chip_latency_s`` once, and the busiest
chip's link needs :math:`\max(\text{in}, \text{out})·b / \text{bandwidth}` per frame to
serialise its messages (no overlap with computation assumed):

.. math:: \Delta t = \text{crossing steps} × t_\text{hop}
          + \max_c \max(\text{in}_c, \text{out}_c)·b / B.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> pl = SimpleNamespace(chip_messages=np.array([[0.0, 4], [2, 0]]), core=np.array([0, 1, 2]),
...                      usage=np.array([[2.0, 0, 0, 48], [1, 0, 0, 24], [3, 0, 0, 0]]),
...                      network_inter_chip=[6.0])
>>> prof = SimpleNamespace(cores_per_chip=2, bits_per_synapse=24, spike_message_bits=32,
...                        inter_chip_bandwidth_bit_s=1e6, inter_chip_latency_s=1e-6, name="b")
>>> rows, summary = chip_rows(pl, prof, 10.0, [{"latency_steps": 100}])
>>> [(r["chip"], r["cores"], r["neurons"], r["synapses"], r["in"], r["out"]) for r in rows]
[(0, 2, 3, 3, 2.0, 4.0), (1, 1, 3, 0, 4.0, 2.0)]
>>> summary["messages_per_frame"], summary["bit_s"], summary["added_latency_s"]
(6.0, 1920.0, 0.000228)
"""

from __future__ import annotations

import numpy as np

__all__ = ["chip_rows"]


def chip_rows(placement, profile, frame_rate_hz: float, latency_rows: list[dict]):
    """``(rows, summary)``: the per-chip table and the inter-chip summary (module docstring).

    Parameters
    ----------
    placement : Placement
        With ``chip_messages`` (a multi-chip profile).
    profile : HardwareProfile
        The board (``cores_per_chip``, ``bits_per_synapse`` and the link fields).
    frame_rate_hz : float
        Frames per second.
    latency_rows : list of dict
        The report's latency rows, one per network in placement order (``latency_steps``).

    Returns
    -------
    rows : list of dict
        ``chip``, ``cores``, ``neurons``, ``synapses``, ``synapse_bits``, ``in``, ``out``
        (messages per frame), ``in_bit_s``, ``out_bit_s``, ``link_utilisation``.
    summary : dict
        ``messages_per_frame``, ``bit_s``, ``message_bits``, ``bandwidth_bit_s``,
        ``busiest_link_bit_s``, ``link_time_s``, ``hop_latency_s``, ``crossing_steps``,
        ``added_latency_s``, ``note``.
    """
    msgs = np.asarray(placement.chip_messages, dtype=np.float64)
    n_chips = len(msgs)
    chip = np.asarray(placement.core) // profile.cores_per_chip
    core_chip = np.arange(len(placement.usage)) // profile.cores_per_chip
    usage = np.zeros((n_chips, placement.usage.shape[1]))
    np.add.at(usage, core_chip, placement.usage)
    cores = np.bincount(core_chip, minlength=n_chips)
    off = msgs - np.diag(np.diag(msgs))
    out, inn = off.sum(axis=1), off.sum(axis=0)
    bits, bw = profile.spike_message_bits, profile.inter_chip_bandwidth_bit_s
    rows = []
    for c in range(n_chips):
        row = {"chip": c, "cores": int(cores[c]), "neurons": int(usage[c, 0]),
               "synapses": int(usage[c, 3] // profile.bits_per_synapse),
               "synapse_bits": int(usage[c, 3]), "in": float(inn[c]), "out": float(out[c])}
        if bits is not None:
            row["in_bit_s"] = float(inn[c]) * bits * frame_rate_hz
            row["out_bit_s"] = float(out[c]) * bits * frame_rate_hz
            if bw is not None:
                row["link_utilisation"] = round(max(row["in_bit_s"], row["out_bit_s"]) / bw, 6)
        rows.append(row)
    total = float(off.sum())
    busiest = float(max(out.max(initial=0.0), inn.max(initial=0.0)))
    link_time = busiest * bits / bw if bits is not None and bw is not None else None
    hop = profile.inter_chip_latency_s
    crossing = sum(int(r["latency_steps"]) for r, x in
                   zip(latency_rows, placement.network_inter_chip, strict=True) if x > 0)
    added = None
    if hop is not None and link_time is not None:
        added = round(crossing * hop + link_time, 12)
    summary = {"chips": int(len(np.unique(chip))), "messages_per_frame": total,
               "bit_s": total * bits * frame_rate_hz if bits is not None else None,
               "message_bits": bits, "bandwidth_bit_s": bw,
               "busiest_link_bit_s": busiest * bits * frame_rate_hz if bits is not None else None,
               "link_time_s": link_time, "hop_latency_s": hop, "crossing_steps": crossing,
               "added_latency_s": added,
               "note": f"the link figures (message bits, bandwidth, hop latency) are those of "
                       f"the {profile.name} profile; see its YAML for which are assumptions"}
    return rows, summary
