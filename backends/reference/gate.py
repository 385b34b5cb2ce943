r"""Closed form of *gated* IF neurons: one excitatory synapse, inhibitory stencils.

A span ``[s_0, s_1)`` of a fire-once population is *gated* when its neurons
integrate without leak or bias (``d_u = 1``, ``d_v = 0``, ``b = 0``, input and
spiking on) and their inputs are

* one :class:`~backends.reference.matrix.MatrixDelivery` of one delay class
  whose weights are non-negative with at most one non-zero per target column
  (the *gate*: at most one excitatory synapse per neuron) — or several from the
  same source with the same delay and layout whose non-zeros together still
  leave each target one source (a weight *split* over projections, as a chip
  with narrow weights stores a large one), and
* any number of :class:`~backends.reference.stencil.StencilDelivery` with
  non-positive kernels (inhibition),

and every source spikes at most once in the span.  Then

.. math:: v[t] = v_0 + \sum_{j:\ a_j \le t} w_j

only rises at the gate's arrival ``c`` (all other arrivals are ``<= 0``), so
with ``v_0 < v_{th}`` a neuron fires at ``c`` iff

.. math:: v_0 + w_{gate} + \sum_{\text{stencils}} \sum_o K[o]\,[a(y + o) \le c] \;\ge\; v_{th}

and never otherwise: one comparison per tap instead of a pass per step.  The
spiking CFAR's OS neurons (``docs/cfar_spiking.md``) are of this form; the
cost no longer grows with the number of steps.  The gate's arrival per target
comes from two deliveries of the gate's spikes (``Σ w`` and ``Σ w a``, one
term each).  Exactness is the closed form's: identical spike steps in int64,
and in float64 whenever the sums are exact (dyadic weights).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from backends.reference.matrix import MatrixDelivery
from backends.reference.neuron import PhaseSpan, StepParams
from backends.reference.stencil import StencilDelivery

if TYPE_CHECKING:
    from backends.reference.plan import SimPlan

__all__ = ["GateInputs", "gate_inputs", "solve_gated"]

_NEVER = np.iinfo(np.int64).max


@dataclass(frozen=True)
class GateInputs:
    """The gate projection and the inhibitory stencils of a gated population."""

    gate: str
    stencils: tuple[str, ...]
    #: Further parts of a split gate (same source, delay and layout as ``gate``).
    split: tuple[str, ...] = ()


def _one_excitatory_per_target(weights) -> bool:
    if sp.issparse(weights):
        w = weights.tocsc()
        return bool((w.data >= 0).all() and (np.diff(w.indptr) <= 1).all())
    return bool((weights >= 0).all() and ((weights != 0).sum(axis=0) <= 1).all())


def gate_inputs(deliveries: Mapping[str, object], incoming: Sequence[str]) -> GateInputs | None:
    """The gated structure of a population's inputs, or None (see the module notes).

    ``incoming`` are the ids of its projections, ``deliveries`` their plans;
    :func:`~backends.reference.plan.build_plan` records the result per population
    (``SimPlan.gates``), so it is decided once, not per run.

    Examples
    --------
    >>> import numpy as np
    >>> from backends.reference import build_plan
    >>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, NeuronParams,
    ...                           Population, SpikingNetwork, StencilProjection)
    >>> net = SpikingNetwork(name="os", n_steps=8, populations=[
    ...     Population(id="in", shape={"r": 5}, source=True),
    ...     Population(id="det", shape={"r": 5},
    ...                params=NeuronParams(du=1.0, dv=0.0, v_th=1.0, reset="fire_once"))],
    ...   projections=[
    ...     StencilProjection(id="train", source="in", target="det", axes=("r",),
    ...                       kernel=np.array([-1.0, 0.0, -1.0]), edge=("clip",)),
    ...     MatrixProjection(id="cut", source="in", target="det", contract=("r",),
    ...                      produce=("r",), weights=1.5 * np.eye(5))],
    ...   encoders=[Encoder(port="x", population="in",
    ...                     code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))])
    >>> build_plan(net).gates["det"]
    GateInputs(gate='cut', stencils=('train',), split=())
    """
    gates, stencils = [], []
    for qid in incoming:
        dl = deliveries[qid]
        if isinstance(dl, StencilDelivery) and all((w <= 0).all() for w in dl.tap_weights):
            stencils.append(qid)
        elif (isinstance(dl, MatrixDelivery) and len(dl.delays) == 1
              and _one_excitatory_per_target(dl.weights[0])):
            gates.append(qid)
        else:
            return None
    # a part without a non-zero weight delivers nothing: it is no part of the gate
    live = [q for q in gates if _any_nonzero(deliveries[q].weights[0])] or gates[:1]
    if not live or not _one_split_gate([deliveries[q] for q in live]):
        return None
    return GateInputs(live[0], tuple(stencils), tuple(live[1:]))


def _any_nonzero(weights) -> bool:
    return bool((weights.data if sp.issparse(weights) else weights).any())


def _one_split_gate(parts: list[MatrixDelivery]) -> bool:
    """Whether the gate matrices are one gate split over projections: the same source,
    delay and layout, and still one excitatory source per target together."""
    first = parts[0]
    if len(parts) == 1:
        return True
    for dl in parts[1:]:
        if (dl.source != first.source or dl.delays != first.delays
                or dl.weights[0].shape != first.weights[0].shape
                or dl.block_shape != first.block_shape or dl.to_target != first.to_target
                or not np.array_equal(dl.rep_of, first.rep_of)
                or not np.array_equal(dl.col_of, first.col_of)):
            return False
    union = sum(sp.csr_matrix(dl.weights[0]) for dl in parts)  # non-negative: no cancelling
    return _one_excitatory_per_target(union)


def is_gated_span(seg: PhaseSpan, params: StepParams) -> bool:
    """Whether ``seg`` integrates without leak or bias with input and spiking on."""
    return (seg.input_on and seg.spiking_on and params.du == 1.0 and params.dv == 0.0
            and seg.bias == 0 and params.scale is None)


def _single(flat: np.ndarray, n: int) -> bool:
    return not flat.size or int(np.bincount(flat, minlength=n).max()) <= 1


def _one_source_currents(dl: MatrixDelivery, flat: np.ndarray, values: Sequence[np.ndarray],
                         n_frames: int) -> list[np.ndarray] | None:
    """``dl.current(0, flat, n_frames, values=x)`` for each ``x`` of ``values``, for a CSR
    that reaches each target from at most one source and events of distinct sources
    (:func:`_single`); None for another matrix.

    Every target entry is then one product ``x · w`` added to ``+0`` — what the
    one-hot sparse product computes, in any order — so the stored entries of each
    event's row are found once and each ``x`` scattered directly, no sparse product.
    """
    w = dl.weights[0]
    if not sp.isspmatrix_csr(w) or (w.nnz and int(np.bincount(w.indices).max()) > 1):
        return None
    rows, cols = dl.event_rows(flat, n_frames)
    start = w.indptr[cols]
    n = w.indptr[cols + 1] - start
    pos = np.repeat(start - (np.cumsum(n) - n), n) + np.arange(int(n.sum()))
    entry, weight = np.repeat(rows, n) * dl.n_out + w.indices[pos], w.data[pos]
    out = []
    for x in values:
        block = np.zeros(n_frames * dl.n_reps * dl.n_out, w.dtype)
        block[entry] += np.repeat(x, n) * weight
        out.append(block.reshape(n_frames, *dl.block_shape).transpose(
            0, *(1 + a for a in dl.to_target)))
    return out


def solve_gated(
    plan: SimPlan, pid: str, gates: GateInputs, seg: PhaseSpan, params: StepParams,
    v: np.ndarray, first: np.ndarray, spikes: dict, n_frames: int, need_u: bool
) -> tuple[np.ndarray, np.ndarray] | None:
    """Solve one gated span; None when a run-time condition fails (use another path).

    Parameters
    ----------
    plan, pid : the plan and the population.
    gates : GateInputs
        From :func:`gate_inputs` (``plan.gates[pid]``).
    seg, params : the span and the population's constants.
    v, first : ndarray
        Membrane at the span start and first spike steps (``-1`` none), flat
        over ``(frames, neurons)``; ``first`` is updated in place.
    spikes : dict
        :class:`~backends.reference.fired.Fired` of every source population solved so far.
    n_frames : int
    need_u : bool
        Whether a later span reads the end current.

    Returns
    -------
    (u, v) at the span end, or None (nothing changed).
    """
    s0, s1 = seg.start, seg.stop
    idle = first < 0
    if (v[idle] >= params.v_th).any():
        return None
    pop = plan.populations[pid]
    shape = (n_frames, *pop.dims)
    dtype = v.dtype
    # the gate: per target, its weight (0 = no spike in the span) and its arrival step; a
    # split gate's parts reach each target from the same source, so their sums do too
    parts = [plan.deliveries[q] for q in (gates.gate, *gates.split)]
    dl = parts[0]
    flat, step = spikes[dl.source].events()
    arrive = step + dl.delays[0]
    keep = (arrive >= s0) & (arrive < s1)
    flat, arrive = flat[keep], arrive[keep]
    if not _single(flat, n_frames * dl.src_size):
        return None
    values = (np.ones(flat.size, dtype), arrive.astype(dtype))
    sums = None
    for part in parts:
        currents = [c.reshape(-1) for c in _one_source_currents(part, flat, values, n_frames)
                    or [part.current(0, flat, n_frames, values=x) for x in values]]
        sums = currents if sums is None else [a + b for a, b in zip(sums, currents, strict=True)]
    w_gate, w_arrive = sums
    open_ = w_gate > 0
    when = np.full(w_gate.size, -1, np.int64)
    when[open_] = np.rint(w_arrive[open_] / w_gate[open_]).astype(np.int64)
    when = when.reshape(shape)
    v_at = v + w_gate
    total = v + w_gate
    u_end = np.zeros(v.shape, v.dtype)
    if need_u:
        last = arrive == s1 - 1
        for part in parts:
            u_end += part.current(0, flat[last], n_frames).reshape(-1)
    for qid in gates.stencils:
        st = plan.deliveries[qid]
        flat_s, step_s = spikes[st.source].events()
        n_src = n_frames * st.src_size
        for k, d in enumerate(st.delays):
            arr = step_s + d
            keep = (arr >= s0) & (arr < s1)
            f, a = flat_s[keep], arr[keep]
            if not _single(f, n_src):
                return None
            arrive_map = np.full(n_src, _NEVER, np.int64)
            arrive_map[f] = a
            arrive_map = arrive_map.reshape(n_frames, *st.src_dims)
            v_at = v_at + st.weight_not_after(k, arrive_map, when).reshape(-1)
            total = total + st.correlate(k, arrive_map != _NEVER).reshape(-1)
            if need_u:
                last = a == s1 - 1
                u_end += st.current(k, f[last], n_frames).reshape(-1)
    fire = idle & open_ & (v_at >= params.v_th)
    first[fire] = when.reshape(-1)[fire]
    return u_end, total
