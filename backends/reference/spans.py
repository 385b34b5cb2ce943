r"""The closed form's span solvers: one phase span of one population, no step loop.

With arrival steps ``a_j = t_j + d_j`` of the synapses ``w_j`` and a span
``[s_0, s_1)`` of ``L`` steps and bias ``b``:

*Silent* (input on, spiking off, ``d_v = 0``, ``d_u ∈ {0, 1}``) — no time loop:

.. math::

    d_u = 0:\quad u_1 &= u_0 + \textstyle\sum_j w_j, \qquad
    v_1 = v_0 + L\,(u_0 + b) + \textstyle\sum_j w_j\,(s_1 - a_j)\\
    d_u = 1:\quad u_1 &= I[s_1 - 1], \qquad v_1 = v_0 + L\,b + \textstyle\sum_j w_j

(sums over arrivals in the span): event-driven (or dense) matrix products
per projection and delay.

*Charging* (input off, ``d_v = 0``): ``u = 0`` and ``v_0 + k\,b`` first reaches
``v_th`` at ``k = \lceil (v_{th} - v_0)/b \rceil`` (checked at ``k-1`` and ``k``).

*Driven* (anything else): the drive histogram ``D[t] = Σ_j w_j [a_j = t]`` of
the span is one delivery over a ``(steps × frames)`` batch — the very
arithmetic of the step engine — and the recurrences run with the step engine's
operation order: ``np.cumsum`` (sequential) for ``d_u ∈ {0, 1}, d_v = 0``, else
:func:`~backends.reference.neuron.neuron_step` over the span.  The caller
cuts long spans into blocks so the histogram stays bounded.

Each solver takes the state at the span start (``u``, ``v`` flat over
``(frames, neurons)``; ``first`` the first spike steps, ``-1`` none, updated in
place) and returns ``(u, v)`` at its end.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from backends.reference.delivery import FEATURE_CURRENTS, Delivery
from backends.reference.fired import Fired
from backends.reference.neuron import NeuronState, PhaseSpan, StepParams, neuron_step

__all__ = ["Arrivals", "charge", "silent", "drive", "driven"]


@dataclass(frozen=True)
class Arrivals:
    """The spikes of one source through one delay class, arriving before ``n_steps``."""

    delivery: Delivery
    k: int
    delay: int
    fired: Fired
    n_steps: int

    @cached_property
    def _sorted(self) -> tuple[np.ndarray, np.ndarray]:
        """``(flat, arrival step)`` sorted by arrival, cut at the window end."""
        flat, step = self.fired.events()
        stop = int(np.searchsorted(step, self.n_steps - self.delay))
        return flat[:stop], step[:stop] + self.delay if self.delay else step[:stop]

    def within(self, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        """The spikes arriving in ``[start, stop)``: ``(flat, arrival step)``."""
        flat, arrive = self._sorted
        lo, hi = np.searchsorted(arrive, (start, stop))
        return flat[lo:hi], arrive[lo:hi]

    def dense_current(self, start: int, stop: int, n_frames: int,
                      weighted: bool) -> np.ndarray | None:
        """The span's current from the source's first-spike steps, no events; or None.

        ``Σ_j w_j (stop − a_j)`` (weighted) or ``Σ_j w_j`` over the arrivals in
        ``[start, stop)``, as ``delivery.current`` of those events with those values
        gives it, bit for bit; None where the source is not a first-spike record or
        the delivery has no dense feature product for them.
        """
        applies, current = FEATURE_CURRENTS.get(type(self.delivery), (None, None))
        if self.fired.first is None or applies is None or not applies(
                self.delivery, self.k, None, n_frames):
            return None
        feature = self.fired.arrival_features(self.delay, start, stop, weighted)
        if not applies(self.delivery, self.k, int(np.count_nonzero(feature)), n_frames):
            return None
        return current(self.delivery, self.k, feature, n_frames)


#: Neurons per block of :func:`charge`'s first-crossing arithmetic: its temporaries stay
#: at a few hundred kB (recycled by ``malloc``), not one array per neuron of the batch each.
CHARGE_BLOCK = 1 << 17


def charge(
    v: np.ndarray, first: np.ndarray, seg: PhaseSpan, params: StepParams, *,
    in_place: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Input off, no leak: ``v`` grows by ``b`` per step; the first crossing is analytic.

    Only neurons that have not fired and end the span at or above threshold
    can cross in it (``v + k b`` is monotone in ``k``, rounding included), so the
    step arithmetic runs on those candidates alone, block by block of
    :data:`CHARGE_BLOCK` neurons (elementwise: the same bits as all at once).  With
    ``in_place`` (the caller owns ``v`` and needs its start values no more) the end
    membranes ``v + n b`` are written into ``v`` block by block, where their type is
    ``v``'s: no array as large as the population is allocated.
    """
    n, b0 = seg.stop - seg.start, seg.bias
    if b0 == 0 and not seg.spiking_on:
        return _zeros(v), v
    b_all = params.per_neuron(b0, v.size)  # per-neuron scales: c·b and c·v_th per neuron
    n_b = n * b_all
    if not v.size:
        return _zeros(v), v + n_b
    v_th_all = params.per_neuron(params.v_th, v.size) if seg.spiking_on else None
    end = None
    for lo in range(0, v.size, CHARGE_BLOCK):
        block = slice(lo, min(lo + CHARGE_BLOCK, v.size))
        end_b = v[block] + (n_b[block] if np.ndim(n_b) else n_b)  # v + n b, per neuron
        if seg.spiking_on:  # reads v's start values of the block before they are replaced
            _cross(v[block], end_b, first[block], seg, params,
                   b_all[block] if np.ndim(b_all) else b_all,
                   v_th_all[block] if np.ndim(v_th_all) else v_th_all)
        if end is None:
            end = v if in_place and end_b.dtype == v.dtype else np.empty(v.shape, end_b.dtype)
        end[block] = end_b
    return _zeros(v), end


def _cross(v: np.ndarray, end: np.ndarray, first: np.ndarray, seg: PhaseSpan,
           params: StepParams, b_all, v_th_all) -> None:
    """:func:`charge`'s first crossings of one block of neurons (``v``, ``end``, ``first``
    and any per-neuron ``b_all``, ``v_th_all`` of that block; ``first`` written)."""
    n, b0 = seg.stop - seg.start, seg.bias
    top = end if b0 > 0 else np.maximum(v + b_all, end)
    idle = np.flatnonzero(top >= v_th_all)
    idle = idle[first[idle] < 0]
    w = v[idle]
    b, v_th = (b0, params.v_th) if params.scale is None else (b_all[idle], v_th_all[idle])
    if b0 > 0:  # k = ceil((v_th - w) / b), in place (float k holds whole numbers)
        k = v_th - w
        if params.integer:
            k = -((-k) // b)
        else:
            k /= b
            np.ceil(k, out=k)
        np.clip(k, 1, n + 1, out=k)
        # the rounding checks: the first k with w + k b >= v_th, as the steps add it
        probe = k - 1
        probe *= b
        probe += w
        k -= (k > 1) & (probe >= v_th)
        np.multiply(k, b, out=probe)
        probe += w
        k += probe < v_th
    else:
        k = np.where(w + b >= v_th, 1, n + 1)
    step = k.astype(np.int64)  # idle neurons have first = −1: write every one
    step += seg.start - 1
    step[step >= seg.stop] = -1
    first[idle] = step


def _zeros(v: np.ndarray) -> np.ndarray:
    """A read-only zero current of ``v``'s shape: one element, broadcast (span solvers only
    read ``u``; writing a fresh 4 MB of zeros per charging span was a tenth of the span)."""
    return np.broadcast_to(np.zeros(1, v.dtype), v.shape)


def silent(
    u: np.ndarray, v: np.ndarray, seg: PhaseSpan, params: StepParams, arrivals: list,
    n_frames: int, dims: tuple[int, ...], need_u: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Input on, spiking off, ``dv = 0``, ``du ∈ {0, 1}``: end state from arrival features.

    With ``du = 0`` and ``need_u`` False the end current (``u + Σ w``) is not
    computed: no later span reads it (the caller checked), saving one product.
    """
    s0, s1 = seg.start, seg.stop
    b = params.per_neuron(seg.bias, u.size) if seg.bias != 0 else seg.bias
    keep_total = need_u or params.du != 0.0  # else nothing adds to it: zeros, not written
    total = np.zeros((n_frames, *dims), u.dtype) if keep_total else None
    shape = (n_frames, *dims)
    second = None  # zeros, allocated when a delivery adds events (or none came)
    for arr in arrivals:
        if (params.du == 0.0 and not need_u
                and (cur := arr.dense_current(s0, s1, n_frames, weighted=True)) is not None):
            # the bulk of a silent stage: no events, no sort
            second = _accumulate(second, cur, shape, u.dtype)
            continue
        if second is None:
            second = np.zeros(shape, u.dtype)
        flat, arrive = arr.within(s0, s1)
        if not flat.size:
            continue
        # unit weights route the silent stage's bulk delivery through the BLAS path (event
        # order is immaterial here: the silent path is exact only where every sum is exact)
        if keep_total:
            total += arr.delivery.current(arr.k, flat, n_frames, values=np.ones(flat.size))
        if params.du == 0.0:
            second += arr.delivery.current(arr.k, flat, n_frames, values=s1 - arrive)
        else:
            last = arrive == s1 - 1
            if last.any():
                second += arr.delivery.current(arr.k, flat[last], n_frames)
    total = total.reshape(u.shape) if keep_total else _zeros(u)
    second = (np.zeros(shape, u.dtype) if second is None else second).reshape(u.shape)
    if params.du == 0.0 and s0 == 0:  # the first span: u = v = 0, skip the zero terms
        return total, second if seg.bias == 0 else second + s1 * b
    if params.du == 0.0:
        return u + total, v + (s1 - s0) * (u + b) + second
    return second, v + (s1 - s0) * b + total


def _accumulate(total: np.ndarray | None, current: np.ndarray, shape: tuple[int, ...],
                dtype) -> np.ndarray:
    """``total += current`` with ``total`` zeros when None: the first current, a new array
    of the dense-feature products (:data:`~backends.reference.delivery.FEATURE_CURRENTS`),
    becomes the total in place as ``0 + current`` (``−0`` turns ``+0`` as the sum makes it),
    instead of a population's zeros plus a copy.

    Examples
    --------
    >>> _accumulate(None, np.array([-0.0, 2.0]), (2,), np.float64).tolist()
    [0.0, 2.0]
    >>> _accumulate(np.array([1.0, 1.0]), np.array([2.0, 3.0]), (2,), np.float64).tolist()
    [3.0, 4.0]
    """
    if total is None:
        if (current.shape == shape and current.dtype == dtype and current.flags.writeable
                and current.flags.c_contiguous):
            current += 0.0
            return current
        total = np.zeros(shape, dtype)
    total += current
    return total


def driven(
    u: np.ndarray, v: np.ndarray, first: np.ndarray, seg: PhaseSpan, params: StepParams,
    arrivals: list, n_frames: int, dims: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Any span: drive histogram by delivery, then the step engine's recurrences."""
    s0, n_t = seg.start, seg.stop - seg.start
    if not seg.input_on:
        return _recur(u, v, first, seg, params, None)
    drive = np.zeros((n_t * n_frames, *dims), u.dtype)
    for arr in arrivals:
        flat, arrive = arr.within(s0, seg.stop)
        if not flat.size:
            continue
        src_size = arr.delivery.src_size
        f, i = np.divmod(flat, src_size)
        batch = np.sort(((arrive - s0) * n_frames + f) * src_size + i)
        drive += arr.delivery.current(arr.k, batch, n_t * n_frames)
    drive = drive.reshape(n_t, -1)
    if params.dv == 0.0 and params.du in (0.0, 1.0):
        cur = np.cumsum(np.vstack([u[None], drive]), axis=0)[1:] if params.du == 0.0 else drive
        vs = np.cumsum(np.vstack([v[None], cur + params.per_neuron(seg.bias, v.size)]),
                       axis=0)[1:]
        if seg.spiking_on:
            cross = vs >= params.per_neuron(params.v_th, v.size)
            hit = cross.any(axis=0) & (first < 0)
            first[hit] = s0 + cross.argmax(axis=0)[hit]
        return cur[-1].copy(), vs[-1].copy()
    return _recur(u, v, first, seg, params, drive)


def drive(arrivals: list, s0: int, s1: int, n_frames: int, dims: tuple[int, ...],
          dtype) -> np.ndarray:
    """The drive histogram of steps ``[s0, s1)``: ``(s1 − s0, frames · size)`` currents
    (as :func:`driven` builds it, for the resonators' closed form)."""
    n_t = s1 - s0
    out = np.zeros((n_t * n_frames, *dims), dtype)
    for arr in arrivals:
        flat, arrive = arr.within(s0, s1)
        if not flat.size:
            continue
        src_size = arr.delivery.src_size
        f, i = np.divmod(flat, src_size)
        batch = np.sort(((arrive - s0) * n_frames + f) * src_size + i)
        out += arr.delivery.current(arr.k, batch, n_t * n_frames)
    return out.reshape(n_t, -1)


def _recur(
    u: np.ndarray, v: np.ndarray, first: np.ndarray, seg: PhaseSpan, params: StepParams,
    drive: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The step engine's own update over the span (general decays)."""
    state = NeuronState(u, v, first >= 0)
    for i, t in enumerate(range(seg.start, seg.stop)):
        fired, state = neuron_step(state, 0 if drive is None else drive[i], params, t)
        first[fired] = t
    return state.u, state.v
