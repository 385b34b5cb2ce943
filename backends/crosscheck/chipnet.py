r"""A saved network in Loihi's integer formats, read from the artifact alone (numpy + json).

This module is the shared half of the two cross-check workers
(``backends/lava/lava_worker.py``, ``backends/nengo_loihi/emulator_worker.py``). They run in
another Python (3.10, numpy 1.26), so it imports nothing of radarsnn: it reads
``manifest.json`` and ``arrays.npz`` (``np.load(allow_pickle=False)``) and re-derives every
synapse and every register value from the number format that ``docs/hardware.md`` documents
for the ``loihi`` profile:

* one radarsnn **state unit** of a population is :math:`S_T = 2^6` raw LSBs of the chip's
  24-bit ``u``/``v`` (the synaptic input is shifted left by 6, ``act_shift``) — or
  :math:`S_T = 1` when the population's weights are all multiples of 64 (a network
  quantized in raw LSBs);
* a weight ``w`` is ``m·2^e`` state units; mixed-sign synapse groups store ``2m``
  (9 bits, lowest bit dropped) with ``weight_exp = e − 1``, one-sign groups store ``m``
  (``|m| ≤ 255``) with ``weight_exp = e``;
* ``v ≥ θ`` (radarsnn) is the chip's ``v > vth·2^6`` with ``vth = (S_T·θ − 1)/64``;
* biases are ``mant·2^exp`` raw LSBs, ``|mant| ≤ 4095``, ``0 ≤ exp ≤ 7``;
* ``du`` (radarsnn, 12-bit) is ``du_chip + 1`` (the current-decay offset); ``du = 0`` has
  no chip value and leaks ``1/4096`` per step.

Each population's spikes reach the next one a step later than in radarsnn (the chips'
dendritic accumulation of step ``t`` is delivered at ``t + 1``), so every population runs
``lag`` steps behind; :func:`chip_network` computes the lags and the delays that keep the
radarsnn arrival times.  What has no chip equivalent raises :class:`NotExpressible`.

Examples
--------
>>> raw_weights(np.array([3.0, -5.0, 0.0]), scale=64)
(array([  6, -10,   0]), -1, 'mixed')
>>> threshold_register(4.0, scale=64), threshold_register(257.0, scale=1)
(3, 4)
>>> bias_register(96.0)
(96, 0)
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["ACT_SHIFT", "ChipNetwork", "ChipPopulation", "ChipProjection", "NotExpressible",
           "bias_register", "chip_network", "raw_weights", "threshold_register"]

#: Left shift of the summed synaptic input and of the threshold (Lava ``act_shift`` and
#: ``vth_shift``; nengo-loihi ``VTH_EXP`` and the ``<< 6`` of ``discretize_weights``).
ACT_SHIFT = 6
#: Largest threshold register (17-bit unsigned ``vth``).
VTH_MAX = (1 << 17) - 1
#: Largest bias mantissa magnitude (13-bit signed) and bias exponent (3-bit unsigned).
BIAS_MANT_MAX, BIAS_EXP_MAX = 4095, 7
#: Largest weight exponent register.
WEIGHT_EXP_MAX = 7


class NotExpressible(ValueError):
    """The network needs a feature the chip's stock neurons or synapses lack."""


def raw_weights(w: np.ndarray, scale: int) -> tuple[np.ndarray, int, str]:
    """Stored weights, the Lava ``weight_exp`` and the sign mode for state-unit weights ``w``.

    The synaptic input of one synapse in raw LSBs is ``stored·2^(weight_exp + 6)``; it must
    equal ``scale·w`` exactly.

    Raises
    ------
    NotExpressible
        A weight that is no whole ``m·2^e`` within the stored width.
    """
    raw = np.asarray(w, np.float64) * scale
    if not raw.any():
        return np.zeros(raw.shape, np.int64), 0, "excitatory"
    mixed = raw.min() < 0 < raw.max()
    mode = "mixed" if mixed else ("excitatory" if raw.max() > 0 else "inhibitory")
    # mixed: 9 bits with the lowest dropped (Lava truncate_weights), mantissa ±127 as
    # nengo-loihi's discretize_weights clips it; a negative exponent right-shifts the summed
    # input (floor), exact only for mixed groups at -1 (every stored weight is even)
    m_max, step, lowest = (127, 2, -1) if mixed else (255, 1, 0)
    for exp in range(lowest, WEIGHT_EXP_MAX + 1):
        m = raw / (2.0 ** (exp + ACT_SHIFT) * step)
        if np.all(m == np.round(m)) and np.abs(m).max() <= m_max:
            return np.round(m).astype(np.int64) * step, exp, mode
    raise NotExpressible(f"weights up to {np.abs(raw).max():g} raw LSBs are no 8-bit "
                         f"mantissa times 2^(6 + weight_exp), weight_exp <= {WEIGHT_EXP_MAX}")


def threshold_register(theta: float, scale: int) -> int:
    """The ``vth`` register for radarsnn's ``v ≥ θ`` (state units), strict ``v > vth << 6``.

    With ``S = 64`` the membrane moves in whole units (64 LSBs), so ``v ≥ θ`` is
    ``v > θ − 1``: ``vth = θ − 1``.  With ``S = 1`` (raw LSBs) ``vth = (θ − 1) / 64``.
    """
    vth = theta - 1 if scale == 1 << ACT_SHIFT else (theta - 1) / (1 << ACT_SHIFT)
    if vth != math.floor(vth) or not 0 <= vth <= VTH_MAX:
        raise NotExpressible(f"threshold {theta:g} (x{scale}) needs vth = {vth:g}: not an "
                             f"integer in 0..{VTH_MAX} (strict v > vth << 6)")
    return int(vth)


def bias_register(raw: float) -> tuple[int, int]:
    """``(bias_mant, bias_exp)`` with ``bias_mant·2^bias_exp == raw`` LSBs."""
    if raw == 0:
        return 0, 0
    for exp in range(BIAS_EXP_MAX + 1):
        m = raw / 2 ** exp
        if m == math.floor(m) and abs(m) <= BIAS_MANT_MAX:
            return int(m), exp
    raise NotExpressible(f"bias {raw:g} raw LSBs is no 13-bit mantissa << 0..7")


@dataclass
class ChipPopulation:
    """One neuron population in registers: raw values per phase segment."""

    id: str
    size: int
    scale: int
    du: int
    dv: int
    leaky_current: bool
    reset: str
    lag: int = 0
    segments: list[dict] = field(default_factory=list)
    theta: float = 1.0
    vth: int = VTH_MAX

    @property
    def gated(self) -> bool:
        """Whether a phase may not spike: the chip's threshold is fixed for a run, so it
        runs at the largest ``vth`` and the decision is read from the membrane."""
        return not all(seg["spiking_on"] for seg in self.segments)


@dataclass
class ChipProjection:
    """One synapse group: dense stored weights ``(n_post, n_pre)``, exponent, delays."""

    id: str
    source: str
    target: str
    weights: np.ndarray
    weight_exp: int
    sign_mode: str
    delays: np.ndarray


@dataclass
class ChipNetwork:
    """A saved network in chip registers (see the module doc)."""

    name: str
    n_steps: int
    sources: dict[str, int]
    populations: dict[str, ChipPopulation]
    projections: list[ChipProjection]
    notes: list[str] = field(default_factory=list)

    @property
    def max_lag(self) -> int:
        """Steps the deepest population runs behind radarsnn."""
        return max((p.lag for p in self.populations.values()), default=0)


def _arrays(folder: Path) -> dict[str, np.ndarray]:
    with np.load(folder / "arrays.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _grouped(shape: list, first: list[str], last: list[str]) -> np.ndarray:
    axes, dims = [a for a, _ in shape], [n for _, n in shape]
    idx = np.arange(int(np.prod(dims))).reshape(dims)
    perm = [axes.index(a) for a in (*first, *last)]
    n_last = int(np.prod([dims[axes.index(a)] for a in last], dtype=np.int64))
    return idx.transpose(perm).reshape(-1, n_last)


def _expand_matrix(entry: dict, arr: dict, src: list, tgt: list):
    get = {k: arr[v["key"]] for k, v in entry["arrays"].items()}
    contract, produce = list(entry["contract"]), list(entry["produce"])
    reps = [a for a, _ in src if a not in contract]
    pre_of, post_of = _grouped(src, reps, contract), _grouped(tgt, reps, produce)
    if "weights" in get:
        rows, cols = np.nonzero(get["weights"])
        w = get["weights"][rows, cols]
        d = get["delays"][rows, cols] if "delays" in get else np.zeros(rows.size, np.int64)
    else:
        live = get["values"] != 0
        rows, cols, w = get["rows"][live], get["cols"][live], get["values"][live]
        d = get["delays"][live] if "delays" in get else np.zeros(rows.size, np.int64)
    n_rep = pre_of.shape[0]
    return (pre_of[:, rows].ravel(), post_of[:, cols].ravel(), np.tile(w, n_rep),
            np.tile(d.astype(np.int64), n_rep))


def _expand_stencil(entry: dict, arr: dict, src: list, tgt: list):
    kernel = arr[entry["arrays"]["kernel"]["key"]]
    delays = arr[entry["arrays"]["delays"]["key"]] if "delays" in entry["arrays"] else None
    taps = np.argwhere(kernel != 0)
    offsets = taps - np.array(kernel.shape) // 2
    w = kernel[tuple(taps.T)]
    d = delays[tuple(taps.T)] if delays is not None else np.zeros(len(taps), np.int64)
    axes, dims = [a for a, _ in tgt], [n for _, n in tgt]
    size = int(np.prod(dims))
    coords = np.unravel_index(np.arange(size), dims)
    valid = np.ones((size, len(taps)), bool)
    src_coord = {}
    for axis, name in enumerate(axes):
        c = np.broadcast_to(coords[axis][:, None], valid.shape)
        if name in entry["axes"]:
            j = entry["axes"].index(name)
            c = c + offsets[None, :, j]
            if entry["edge"][j] == "wrap":
                c = c % dims[axis]
            else:
                valid &= (c >= 0) & (c < dims[axis])
                c = np.clip(c, 0, dims[axis] - 1)
        src_coord[name] = c
    src_axes, src_dims = [a for a, _ in src], [n for _, n in src]
    pre = np.ravel_multi_index(tuple(src_coord[a] for a in src_axes), src_dims)
    post = np.broadcast_to(np.arange(size)[:, None], valid.shape)
    return (pre[valid], post[valid], np.broadcast_to(w, valid.shape)[valid],
            np.broadcast_to(d, valid.shape)[valid].astype(np.int64))


EXPAND = {"matrix": _expand_matrix, "stencil": _expand_stencil}


def _size(shape: list) -> int:
    return int(np.prod([n for _, n in shape], dtype=np.int64))


def chip_network(folder: str | Path) -> ChipNetwork:
    """Read a saved network (``backends.save``) into chip registers.

    Raises
    ------
    NotExpressible
        A projection kind, neuron setting, weight, threshold or bias with no chip value.
    """
    folder = Path(folder)
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    arr = _arrays(folder)
    pops = {p["id"]: p for p in manifest["populations"]}
    n_steps = int(manifest["network"]["n_steps"])
    expanded = []
    for entry in manifest["projections"]:
        if entry["kind"] not in EXPAND:
            raise NotExpressible(f"projection {entry['id']!r} of kind {entry['kind']!r}: "
                                 "no stock Loihi 1 synapse group (matrix and stencil only)")
        src, tgt = pops[entry["source"]], pops[entry["target"]]
        pre, post, w, d = EXPAND[entry["kind"]](entry, arr, src["shape"], tgt["shape"])
        expanded.append((entry, pre, post, w, d))
    notes: list[str] = []
    out: dict[str, ChipPopulation] = {}
    for pid, p in pops.items():
        if p["source"]:
            continue
        incoming = np.concatenate([w for e, _, _, w, _ in expanded if e["target"] == pid]
                                  or [np.zeros(0)])
        scale = 1 if incoming.size and np.all(np.mod(incoming, 64) == 0) else 64
        out[pid] = _population(pid, p, scale, n_steps, notes)
    _set_lags(out, pops, expanded)
    projections = []
    for entry, pre, post, w, d in expanded:
        tgt = out[entry["target"]]
        src_lag = out[entry["source"]].lag if entry["source"] in out else 0
        delay = d + tgt.lag - src_lag - 1
        stored, exp, mode = raw_weights(w, tgt.scale)
        n_pre, n_post = _size(pops[entry["source"]]["shape"]), tgt.size
        dense = np.zeros((n_post, n_pre), np.int64)
        dly = np.zeros((n_post, n_pre), np.int64)
        np.add.at(dense, (post, pre), stored)
        dly[post, pre] = delay
        if np.abs(dense).max(initial=0) > (256 if mode == "mixed" else 255):
            raise NotExpressible(f"projection {entry['id']!r}: two synapses on one pair "
                                 "add beyond the stored width")
        projections.append(ChipProjection(entry["id"], entry["source"], entry["target"],
                                          dense, exp, mode, dly))
    sources = {pid: _size(p["shape"]) for pid, p in pops.items() if p["source"]}
    return ChipNetwork(manifest["network"]["name"], n_steps, sources, out, projections, notes)


def _population(pid: str, p: dict, scale: int, n_steps: int, notes: list[str]) -> ChipPopulation:
    q = p["params"]
    if q.get("scale_axis"):
        raise NotExpressible(f"population {pid!r}: per-neuron parameter scales (write each "
                             "neuron's registers separately; not done by this cross-check)")
    if q["reset"] == "subtract":
        notes.append(f"{pid}: subtractive reset; the stock LIF resets v to 0")
    if q["reset"] == "value" and q["v_reset"] != 0:
        raise NotExpressible(f"population {pid!r}: reset to {q['v_reset']:g}; the stock "
                             "LIF resets v to 0")
    if q["reset"] == "fire_once":
        notes.append(f"{pid}: fire-once; the stock LIF fires again (first spikes compared)")
    du_units, dv_units = round(q["du"] * 4096), round(q["dv"] * 4096)
    leaky = du_units == 0
    if leaky:
        notes.append(f"{pid}: du = 0 (non-leaking current) leaks 1/4096 per step on the chip")
    if scale != 1 and (0 < du_units < 4096 or dv_units > 0):
        notes.append(f"{pid}: a decay on 64-LSB state units: the chip truncates in LSBs, "
                     "radarsnn in units (quantize in raw LSBs, weights x64, to be exact)")
    if dv_units == 4096:
        raise NotExpressible(f"population {pid!r}: dv = 1 (12-bit dv stops at 4095)")
    segs = []
    starts = [ph["start_step"] for ph in q["phases"]] + [n_steps]
    for ph, start, stop in zip(q["phases"], starts, starts[1:], strict=False):
        if start >= n_steps:
            break
        mant, exp = bias_register(scale * ph["bias"])
        segs.append({"start": start, "stop": min(stop, n_steps), "bias_mant": mant,
                     "bias_exp": exp, "input_on": bool(ph["input_on"]),
                     "spiking_on": bool(ph["spiking_on"])})
    size = _size(p["shape"])
    gated = not all(seg["spiking_on"] for seg in segs)
    if gated:
        notes.append(f"{pid}: spiking switched off in a phase; the chip's threshold is fixed "
                     "for a run: decided from the membrane (v >= theta on the spiking steps)")
    vth = VTH_MAX if gated else threshold_register(q["v_th"], scale)
    return ChipPopulation(pid, size, scale, max(du_units - 1, 0), dv_units, leaky,
                          q["reset"], 0, segs, float(q["v_th"]), vth)


def _set_lags(out: dict, pops: dict, expanded: list) -> None:
    """Each population's lag: one step more than its latest source (sources: 0), at least 1
    (so that every host write comes after the first chip step)."""
    for pop in out.values():
        pop.lag = 1
    for _ in range(len(out) + 1):
        changed = False
        for entry, *_ in expanded:
            src, tgt = entry["source"], entry["target"]
            if src == tgt:
                continue
            lag = (out[src].lag if src in out else 0) + 1
            if lag > out[tgt].lag:
                out[tgt].lag, changed = lag, True
        if not changed:
            return
    raise NotExpressible("a recurrent loop through several populations (lags diverge)")
