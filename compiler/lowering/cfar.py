r"""Lowering ``cfar`` into time-coded threshold neurons: spiking OS- and CA-CFAR, 1D and 2D.

One neuron per cell under test (CUT), in a population with exactly the CFAR
input's axes.  The input map is encoded once (one latency spike per cell, see
:mod:`compiler.lowering.cfar_codes`) and reaches the neurons through two
projections:

* the **training stencil** — one kernel shared by every CUT, built from
  :func:`radar.cfar_window.training_mask` (guard cells and the CUT unconnected), with
  ``wrap``/``clip`` per axis; a clipped CUT simply has ``n_avail < N`` synapses;
* the **CUT projection** — a diagonal (one synapse per neuron, from its own
  cell) whose per-neuron weight carries the clip-edge renormalisation.

OS-CFAR (``kind: os``)
    IF neuron (``du = 1``, ``dv = 0``, fire-once, ``v_th = 1``, always listening; on a
    target without fire-once a reset to 0, which is the same here: every input cell spikes
    once and only the CUT weight is positive, so after the spike the membrane only falls);
    training weight ``−1``; CUT weight ``k_eff + 1/2`` (``k_eff`` on a target with integer
    weights, where no float tie exists) with delay ``D``; log latency
    code in which ``α`` is the delay ``D``.  Fires when the CUT spike arrives iff
    fewer than ``k_eff`` training spikes came no later.
CA-CFAR (``kind: ca``)
    Ramp neuron (``du = dv = 0``, fire-once): input on / spiking off for ``T``
    steps, then one decision step with input off; training weight ``−α``; CUT
    weight ``n_avail`` with delay ``d``; linear latency code whose offset is folded
    into ``d``.  Fires at step ``T`` iff ``v = c(n_avail x_CUT − α Σ x_j) > 0``.

OS: the membrane when the CUT arrives is ``k_eff + 1/2 − B`` with ``B`` the
training spikes arrived so far (same-step arrivals are summed before the
threshold test); it reaches ``1`` iff ``B <= k_eff − 1``, i.e. iff fewer than
``k_eff`` training cells satisfy ``α x_j >= x_CUT``, i.e. iff
``x_CUT > α · x_(k_eff)`` — the half is a margin that no integer count can
cross.  CA: ``v > 0`` is tested as ``v >= 2**-1022`` (no float lies between).

Output: the population's spikes are the detection mask (decoder kind
``spiked``, 1.0 = detection), a :class:`~compiler.lowering.SpikeValue` that
later motifs consume.  Compile options read: ``time_steps`` (total steps,
default 100), ``cfar_ties`` (``balanced`` | ``exact``, OS only),
``cfar_range`` (``(x_lo, x_hi)`` or ``{node: (x_lo, x_hi)}``, overrides the
calibration), ``cfar_quantiles`` (range quantiles, default
:data:`~compiler.lowering.cfar_codes.RANGE_QUANTILES`).  The code chosen is
recorded in the network's ``meta["cfar"][node]``.

Examples
--------
>>> from ir import Graph
>>> from compiler.lowering import LoweringContext, LoweringRegistry, lower_graph
>>> from compiler.lowering.inputs import register_io
>>> g = Graph.from_dict({"name": "c", "nodes": [
...     {"id": "x", "op": "input", "shape": {"range": 16}, "domain": "power"},
...     {"id": "det", "op": "cfar", "input": "x", "kind": "os", "guard": 1, "train": 2,
...      "k": 3, "alpha": 2.0},
...     {"id": "o", "op": "output", "input": "det"}]})
>>> reg = LoweringRegistry(); register_io(reg); register_cfar(reg)
>>> from compiler.compile import motif_settings
>>> ctx = LoweringContext(graph=g, registry=reg, settings=motif_settings({"cfar_range": (0.1, 10)}))
>>> net = lower_graph(ctx)[0].network
>>> net.n_neurons, net.n_synapse_instances(), net.meta["cfar"]["det"]["code"]["kind"]
(16, 80, 'log')
"""

from __future__ import annotations

import math

import numpy as np

from compiler.lowering.cfar_codes import (
    RANGE_QUANTILES,
    ca_linear_code,
    input_range,
    os_log_code,
)
from compiler.lowering.context import LoweringContext
from compiler.lowering.options import CfarOptions
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.values import Value
from compiler.snn import Decoder, NeuronParams, Phase, SpikingNetwork
from ir.errors import CompileError
from ir.ops import CFAR
from radar.cfar_window import effective_k, training_counts, training_mask

__all__ = ["MOTIF", "DEFAULT_STEPS", "register_cfar", "lower_cfar", "cfar_counters",
           "cfar_op_counts"]

#: The motif name of the time-coded CFAR.
MOTIF = "time"

#: Total time steps of a CFAR network when the compile option ``time_steps`` is not set.
DEFAULT_STEPS = CfarOptions().time_steps  # declared in compiler.lowering.options

#: ``v > 0`` as a threshold: the smallest positive normal float64 (``2**-1022``).
_POSITIVE = float(np.finfo(np.float64).tiny)


def _range(ctx: LoweringContext, node: str, source: str,
           kind: str) -> tuple[float, float, str, bool]:
    """The code's range, where it came from, and whether its top saturates on purpose."""
    given = ctx.settings_of(CfarOptions).cfar_range
    if isinstance(given, dict):
        given = given.get(node)
    if given is not None:
        lo, hi = (float(v) for v in given)
        if not (math.isfinite(lo) and math.isfinite(hi) and hi > max(lo, 0.0)):
            raise CompileError(f"node {node!r} (cfar): cfar_range={given!r} must be finite with "
                               "x_hi > max(x_lo, 0)", node=node)
        return lo, hi, "option", False
    quantiles = ctx.settings_of(CfarOptions).cfar_quantiles
    if isinstance(quantiles, dict):  # per node id or per CFAR kind
        quantiles = quantiles.get(node, quantiles.get(kind))
    quantiles = tuple(quantiles or RANGE_QUANTILES[kind])
    lo, hi, how = input_range(ctx.calibration.get(source), quantiles, node=node, source=source)
    return lo, hi, how, how == "quantiles" and float(quantiles[1]) < 1.0


def lower_cfar(ctx: LoweringContext, node: str, op: CFAR, inputs: list[Value]) -> Value:
    """Lower one ``cfar`` node into a time-coded detection population (see module docstring).

    Parameters
    ----------
    ctx : LoweringContext
        The lowering state (options, calibration, the open network).
    node : str
        The CFAR node id.
    op : CFAR
        Its parameters.
    inputs : list of Value
        The map (host value or spikes; spikes are decoded at a host boundary).

    Returns
    -------
    SpikeValue
        The detection mask: population ``"<node>/det"``, decoder kind ``spiked``.

    Raises
    ------
    CompileError
        No range for the code (no calibration, no ``cfar_range``), a bad tie rule,
        or a time budget too small.
    """
    (value,) = inputs
    t_in = ctx.types[value.node]
    win = op.window(node, t_in)
    alpha = op.alpha_for(win.n_train)
    settings = ctx.settings_of(CfarOptions)
    n_steps = settings.cfar_steps or settings.time_steps
    lo, hi, how, saturate = _range(ctx, node, value.node, op.kind)
    map_shape = tuple(t_in.axes[a] for a in win.axes)
    n_avail = training_counts(map_shape, guard=list(win.guard), train=list(win.train),
                              edge=list(win.edge))
    if op.kind == "os":
        code, cut_delay, train_delay, info = os_log_code(
            lo, hi, alpha=alpha, n_steps=n_steps, ties=ctx.settings_of(CfarOptions).cfar_ties)
        # each input cell spikes once and only the CUT's weight is positive: after its spike
        # the membrane only falls, so a reset to 0 is fire-once (stock neurons: no fire-once)
        stock = ctx.target.fire_once == "none"
        params = NeuronParams(du=1.0, dv=0.0, v_th=1.0, reset="value" if stock else "fire_once")
        # integer targets: the membrane k_eff − B is a whole number, so k_eff itself decides
        # exactly (B <= k_eff − 1) and the quantize pass can store it without rounding
        integer = ctx.target.number_format.integer
        cut_w = effective_k(op.k, n_avail, win.n_train) + (0.0 if integer else 0.5)
        train_w = -1.0
    else:
        code, cut_delay = ca_linear_code(lo, hi, alpha=alpha, n_steps=n_steps)
        train_delay, info = 0, {}
        params = NeuronParams(du=0.0, dv=0.0, v_th=_POSITIVE, reset="fire_once", phases=(
            Phase(start_step=0, spiking_on=False),
            Phase(start_step=code.t_max, input_on=False)))
        cut_w = n_avail.astype(np.float64)
        train_w = -alpha
    # encode first: decoding a spiking input to the host closes the open network, and the
    # builder must be the one the encoder's population lives in
    src = ctx.encode(value, consumer=node, code=code, motif=MOTIF, saturate=saturate)
    builder = ctx.builder()
    det = builder.population(node, "det", dict(t_in.axes), params, motif=MOTIF)
    kernel = train_w * training_mask(list(win.guard), list(win.train)).astype(np.float64)
    builder.stencil(node, "train", src.id, det.id, axes=win.axes, kernel=kernel, edge=win.edge,
                    motif=MOTIF, delays=np.full(kernel.shape, train_delay, np.int64))
    n_map = int(np.prod(map_shape))
    diag = np.arange(n_map)
    builder.matrix(node, "cut", src.id, det.id, contract=win.axes, produce=win.axes,
                   motif=MOTIF, rows=diag, cols=diag, values=cut_w.ravel(),
                   n_in_out=(n_map, n_map), delays=np.full(n_map, cut_delay, np.int64))
    builder.meta.setdefault("cfar", {})[node] = {
        "kind": op.kind, "alpha": alpha, "n_train": win.n_train, "k": op.k,
        "axes": list(win.axes), "edge": list(win.edge), "n_steps": n_steps,
        "code": code.model_dump(), "cut_delay": cut_delay, "train_delay": train_delay,
        "range": {"x_lo": lo, "x_hi": hi, "from": how}, **info}
    return ctx.spike_value(node, det, Decoder(port=node, population=det.id, kind="spiked"),
                           (0, n_steps), kind="detections", motif=MOTIF)


def register_cfar(registry: LoweringRegistry) -> None:
    """Register the time-coded CFAR motif ``time`` (the default for ``cfar``)."""
    registry.register(CFAR, MOTIF, lower_cfar, default=True)


def cfar_counters(network: SpikingNetwork, node: str) -> dict[str, int]:
    """Counters of one lowered CFAR node, read from the compiled network.

    Parameters
    ----------
    network : SpikingNetwork
        The network holding the node's ``"<node>/det"`` population.
    node : str
        The CFAR node id.

    Returns
    -------
    dict
        ``neurons`` (CUT neurons), ``inputs`` (encoded cells), ``synapses`` (per-CUT synapse
        instances of the node's projections, every stencil position counted), ``synapses_per_cut``
        (``synapses // neurons``, i.e. ``N_train + 1`` for an interior CUT), ``n_train``,
        ``n_steps``.

    Examples
    --------
    See :func:`cfar_op_counts`.
    """
    pops = network.population
    det, src = pops[f"{node}/det"], pops[f"{node}/in"]
    mine = [p for p in network.projections if p.origin.get("node") == node]
    sub = SpikingNetwork(name=node, n_steps=network.n_steps, populations=[det, src],
                         projections=mine)
    synapses = sub.n_synapse_instances()
    per_cut = synapses // det.size
    return {"neurons": det.size, "inputs": src.size, "synapses": synapses,
            "synapses_per_cut": per_cut, "n_train": per_cut - 1, "n_steps": network.n_steps}


def cfar_op_counts(kind: str, n_train: int, n_steps: int) -> dict[str, dict[str, int]]:
    """Operations per CUT of conventional and spiking CFAR (Vogginger et al. 2022, Table 1).

    Parameters
    ----------
    kind : {"os", "ca"}
    n_train : int
        Training cells per CUT (from :func:`cfar_counters`).
    n_steps : int
        Time steps of the spiking network.

    Returns
    -------
    dict
        ``{"conventional": {...}, "spiking": {...}}``, each with ``add``, ``cmp``, ``total``.
        Conventional OS: ``N+1`` compares; CA: ``N`` adds and one compare.  Spiking OS:
        ``N`` synaptic events (adds) and one threshold compare per step; spiking CA: ``N``
        events plus one ramp integration per step, one compare per step.

    Examples
    --------
    >>> [cfar_op_counts(k, 176, s)["spiking"]["total"] for k, s in (("os", 100), ("ca", 500))]
    [276, 1176]
    >>> [cfar_op_counts(k, 176, 1)["conventional"]["total"] for k in ("os", "ca")]
    [177, 177]
    """
    if kind == "os":
        conv, spk = (0, n_train + 1), (n_train, n_steps)
    elif kind == "ca":
        conv, spk = (n_train, 1), (n_train + n_steps, n_steps)
    else:
        raise CompileError(f"cfar kind {kind!r} is not 'os' or 'ca'")
    return {name: {"add": a, "cmp": c, "total": a + c}
            for name, (a, c) in (("conventional", conv), ("spiking", spk))}
