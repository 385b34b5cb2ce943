r"""The closed form of a resonator population: every resonator, repetition and frame at once.

The state is one complex array ``z`` of shape ``(R, K, P)`` — ``K`` the bins of the
resonator axis, ``R`` the frames times the axes before it, ``P`` the axes after it — and
the drive (:mod:`backends.reference.resonator_drive`) broadcasts over ``K`` when every bin
receives the same input.  Per input span:

*Floating point* (``coef_bits = 0``): the recurrence is linear,

.. math:: z(s_1) = a^{m} z(s_0) + \sum_{j=0}^{m-1} a^{m - j}\, d_{s_0 + j}
          \qquad (m = s_1 - s_0,\ a^k = ρ^k e^{ikθ}),

so a span is one matrix product of the drive ``(R·P) × m`` with the power table
``m × K`` (a Vandermonde matrix shared by every repetition and frame); it agrees with the
step engine to rounding.

*Fixed point* (``coef_bits = F > 0``): each step rounds, ``z ← rnd((C + iS)(z + d)/2^F)``
half away from zero per component, so the steps are replayed — each one a few operations
over the whole ``(R, K, P)`` array, in row blocks that stay in the cache.  The arithmetic
is float64 and exact: with whole ``z`` and ``d``, ``u = (C + iS)(z + d)/2^F`` is a
multiple of ``2^{-F}`` computed without rounding while ``2^{F+1}|z + d| < 2^{52}``, and
rounding half away from zero is ``rint(u·(1 + 2^{-51}))``: the factor moves an exact half
``2^{-51}|u| ≥ 2`` ulps away from zero, and any other ``u`` by less than ``2^{-50}|u|``,
which stays below the ``2^{-F}`` between ``u`` and the nearest half while
``|u| < 2^{49-F}``.  Both conditions are checked before the replay from a bound on
``|z|`` (``|z| ← |a|(|z| + max|d|) + 1``, with ``|d| ≤ √2·max(|Re d|, |Im d|)`` per step);
where they fail the step arithmetic (:func:`~backends.reference.resonator.rotate`, int64
or float64) runs instead, as it does for fractional drives in float64.  Either way the
result is the step engine's, bit for bit (``tests/test_resonator_closed.py``).

*Cost per step and row block* (``rb × K × P`` entries): the rotation is three in-place
passes — the complex product by ``a``, the factor ``1 + 2^{-51}``, ``rint`` — which is the
floor of :func:`backends.reference.floor.rotation_floors`; the drive adds a fourth, since
each step's drive enters before that step's rounding (no two steps' drives can be summed
first).  A drive shared along the bins is added as a rank-one update (``zgeru``: the ``(K,
rb)`` view plus ``1 ⊗ d_j`` when ``P = 1``, else the ``(P, K)`` view of each row plus
``d_{j,r} ⊗ 1``), BLAS calls prepared once per block.  The drive itself comes from the
stream source's levels (:mod:`backends.reference.level_drive`), never from its bit planes.

Examples
--------
>>> u = np.array([2.5, -2.5, 1.5, -1.5, 2.25, -2.75])  # multiples of 2^-2
>>> np.rint(u * _AWAY).tolist()  # half away from zero
[3.0, -3.0, 2.0, -2.0, 2.0, -3.0]
"""

from __future__ import annotations

import threading
import weakref

import numpy as np
from scipy.linalg.blas import zgeru as _zgeru

from backends.reference.plan import SimPlan
from backends.reference.resonator import ResonatorStepParams, rotate
from backends.reference.resonator_drive import fold, shared_drive
from backends.reference.spans import charge, drive
from compiler.snn.resonator import N_COMPARTMENTS

__all__ = ["solve_resonators", "replay_rows", "input_layout"]

#: ``1 + 2^-51``: ``rint(u · _AWAY)`` rounds a multiple of ``2^-F`` half away from zero.
_AWAY = 1.0 + 2.0 ** -51
#: Complex entries of one row block of the replay (about 512 kB: it stays in L2).
_BLOCK_ENTRIES = 1 << 15
#: The block when other threads of the process run too (a frames axis on several workers):
#: every numpy call of the replay hands the interpreter lock to the other thread and back,
#: so fewer, larger calls (2 MiB blocks) keep the threads busy; the bits are the same.
_SHARED_BLOCK_ENTRIES = 1 << 17
#: Resonators × steps of one full drive histogram (a drive not shared along the bins): its
#: four compartments in float64 take 8 MiB.
_FULL_ENTRIES = 1 << 18
#: ``√2`` rounded up: ``|d| ≤ _SQRT2 · max(|Re d|, |Im d|)``.
_SQRT2 = 1.4142135623730951 * (1.0 + 2.0 ** -50)
#: :func:`input_layout` per plan's population parameters.
_LAYOUTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def solve_resonators(plan: SimPlan, pid: str, arrivals: list, n_frames: int,
                     first: np.ndarray) -> np.ndarray:
    """End membranes (flat) of resonator population ``pid``; fills ``first`` (spike steps).

    Parameters
    ----------
    plan : SimPlan
    pid : str
        A population with :class:`~backends.reference.resonator.ResonatorStepParams`.
    arrivals : list of Arrivals
        Its incoming spikes (:class:`backends.reference.spans.Arrivals`).
    n_frames : int
    first : ndarray of int64
        First spike step per compartment (−1: none), filled in place.
    """
    params: ResonatorStepParams = plan.neurons[pid]
    pop = plan.populations[pid]
    dtype = np.int64 if plan.integer else np.float64
    n = n_frames * pop.size

    def full(s0: int, s1: int) -> np.ndarray:
        return drive(arrivals, s0, s1, n_frames, pop.dims, dtype)

    (lead, k, tail), coefs = input_layout(plan, pid)
    shape = (n_frames * lead, k, tail)
    z = np.zeros(shape, np.complex128)
    v = None  # (the compartments of z once an input span ran)
    for seg in params.spans:
        if not seg.input_on:
            _, v = charge(np.zeros(n, dtype) if v is None else v, first, seg, params)
            continue
        shared = shared_drive(plan, pid, arrivals, n_frames, seg.start, seg.stop)
        blocks = ([(seg.start, shared.reshape(-1, shape[0], 1, tail))]
                  if shared is not None else _full_blocks(full, seg, shape))
        for s0, d in blocks:  # (a shared drive is whole in fixed point: resonator_drive)
            z = (_linear(z, d, coefs[0]) if not params.coef_bits
                 else _replay(z, d, s0, params, coefs, whole=shared is not None))
        v = _project(z, dtype)
    return np.zeros(n, dtype) if v is None else v


def input_layout(plan: SimPlan, pid: str) -> tuple[tuple[int, int, int],
                                                  tuple[np.ndarray, np.ndarray | None]]:
    """``((lead, K, P), (a, a_end))`` of resonator population ``pid``: one frame's state is
    ``(lead, K, P)`` (the axes before the resonator axis, its bins, the axes after it but
    ``part``); ``a`` and ``a_end`` are ``(K, P)`` complex, divided by ``2^F`` in fixed point
    (``a_end`` None without renormalisation); computed once per plan's population (read-only
    arrays)."""
    params = plan.neurons[pid]
    if params not in _LAYOUTS:
        _LAYOUTS[params] = _layout(plan, pid)
    return _LAYOUTS[params]


def _layout(plan: SimPlan, pid: str):
    params = plan.neurons[pid]
    pop = plan.populations[pid]
    at = pop.axes.index(plan.network.population[pid].params.axis)
    lead, k, tail = int(np.prod(pop.dims[:at])), pop.dims[at], int(np.prod(pop.dims[at + 1:-1]))
    scale = 2.0 ** -params.coef_bits

    def of(c, s):
        return ((np.asarray(c, np.float64) + 1j * np.asarray(s, np.float64)) * scale).reshape(
            lead, k, tail)[0].copy()

    end = of(params.cos_end, params.sin_end) if params.renorm is not None else None
    coefs = (of(params.cos, params.sin), end)
    for c in coefs:
        if c is not None:
            c.setflags(write=False)
    return (lead, k, tail), coefs


def _full_blocks(full, seg, shape):
    """The full drive histogram in blocks of steps: ``(s0, (m, R, K, P) complex)``."""
    size = shape[0] * shape[1] * shape[2]
    chunk = max(1, _FULL_ENTRIES // size)
    for s0 in range(seg.start, seg.stop, chunk):
        s1 = min(seg.stop, s0 + chunk)
        yield s0, fold(full(s0, s1).reshape(s1 - s0, *shape, N_COMPARTMENTS))


def _linear(z: np.ndarray, d: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``a^m z + Σ_j a^{m−j} d_j``: the power table times the drive (float arithmetic)."""
    m = d.shape[0]
    rho, theta = np.abs(a), np.angle(a)
    k = np.arange(m, 0, -1, dtype=np.float64)[:, None, None]  # a^(m − j), j = 0 … m−1
    table = rho[None] ** k * np.exp(1j * k * theta[None])  # (m, K, P)
    out = z * (rho ** m * np.exp(1j * m * theta))
    if d.shape[2] == 1:  # shared drive: one product per trailing index p
        lhs = d[:, :, 0, :].transpose(2, 1, 0)  # (P, R, m)
        out += np.matmul(lhs, table.transpose(2, 0, 1)).transpose(1, 2, 0)
    else:
        out += np.einsum("jrkp,jkp->rkp", d, table)
    return out


def _replay(z: np.ndarray, d: np.ndarray, s0: int, params: ResonatorStepParams,
            coefs: tuple[np.ndarray, np.ndarray | None], whole: bool = False) -> np.ndarray:
    """The fixed-point steps ``s0 … s0 + m − 1`` (see the module docstring); ``whole``: the
    drive is known to be whole (not checked again)."""
    m = d.shape[0]
    a, a_end = coefs
    ends = (params.renorm[s0:s0 + m] if params.renorm is not None
            else np.zeros(m, bool))
    if not _exact(z, d, a, a_end, params.coef_bits, whole):
        return _replay_steps(z, d, s0, params, coefs)
    return replay_rows(z, a, m, d, a_end, ends)


def replay_rows(z: np.ndarray, a: np.ndarray, n_steps: int, drive: np.ndarray | None = None,
                a_end: np.ndarray | None = None, ends: np.ndarray | None = None,
                block_entries: int | None = None) -> np.ndarray:
    """``n_steps`` fixed-point rotations of ``z`` (``(R, K, P)``, whole values) by ``a``
    (``(K, P)``, already divided by ``2^F``), in row blocks that stay in the cache: per step
    ``z ← rint((z + drive[j])·a·(1 + 2^-51))`` (``a_end`` where ``ends[j]``).  Exact only
    where :func:`_exact` holds; :mod:`backends.reference.floor` times it without a drive,
    in the cache-sized blocks.  ``block_entries`` (complex entries per block; the result is
    the same for any): None picks :data:`_BLOCK_ENTRIES` on a thread of its own and
    :data:`_SHARED_BLOCK_ENTRIES` while other threads of the process run.

    Examples
    --------
    >>> z = np.array([[[3 + 0j]]])
    >>> replay_rows(z, np.array([[0.5j]]), 2).tolist()  # 3 → 1.5i → 2i → −1
    [[[(-1+0j)]]]
    """
    out = np.empty_like(z)
    if block_entries is None:
        block_entries = _BLOCK_ENTRIES if threading.active_count() == 1 else _SHARED_BLOCK_ENTRIES
    rows = max(1, block_entries // (z.shape[1] * z.shape[2]))
    coef = [a_end if ends is not None and ends[j] else a for j in range(n_steps)]
    for r0 in range(0, z.shape[0], rows):
        block = z[r0:r0 + rows].copy()
        flat = block.view(np.float64)
        add = None if drive is None else _drive_adder(block, drive[:n_steps, r0:r0 + rows])
        for j in range(n_steps):
            if add is not None:
                add(j)
            np.multiply(block, coef[j], out=block)
            np.multiply(flat, _AWAY, out=flat)
            np.rint(flat, out=flat)
        out[r0:r0 + rows] = block
    return out


def _drive_adder(block: np.ndarray, part: np.ndarray):
    """``add(j)``: ``block += part[j]`` in place (``block`` ``(rb, K, P)``, ``part``
    ``(m, rb, 1 | K, P)``).  A drive shared along the bins is added as rank-one updates
    (BLAS ``zgeru`` on F-ordered views of ``block``: ``1·d`` is ``d``, the sums are the same
    exact sums), which skip numpy's per-row broadcasting; else a plain ``+=``."""
    rb, k, p = block.shape
    if part.shape[2] != 1 or (p > 1 and rb > 8):
        return lambda j: np.add(block, part[j], out=block)
    ones = np.ones(k, np.complex128)
    if p == 1:  # one update of the (K, rb) view per step: x = ones, y = the rows' drives
        views = [(block.reshape(rb, k).T, part.reshape(len(part), rb))]
    else:  # one per row: the (P, K) view of row r, x = its drives along P, y = ones
        views = [(block[r].T, part[:, r, 0, :]) for r in range(rb)]
    first = views[0][0]
    probe = _zgeru(0.0, np.zeros(first.shape[0], np.complex128),
                   np.zeros(first.shape[1], np.complex128), a=first, overwrite_a=True)
    if not np.shares_memory(probe, first):  # pragma: no cover (scipy would copy)
        return lambda j: np.add(block, part[j], out=block)
    if p == 1:
        view, ys = views[0]
        return lambda j: _zgeru(1.0, ones, ys[j], a=view, overwrite_a=True)

    def add(j: int) -> None:
        for view, xs in views:
            _zgeru(1.0, xs[j], ones, a=view, overwrite_a=True)
    return add


def _exact(z, d, a, a_end, bits: int, whole: bool = False) -> bool:
    """Whether the float64 replay is exact: whole drives (checked unless ``whole``),
    ``2^{F+1}|z̃| < 2^{52}`` and ``|u| < 2^{49−F}`` for the bound ``|z̃|`` of every step's
    ``z + d`` (``|d|`` bounded by ``√2`` times its largest component)."""
    if not whole and not np.array_equal(d, np.rint(d)):
        return False
    growth = max(float(np.abs(a).max()), float(np.abs(a_end).max()) if a_end is not None
                 else 0.0)
    top = _SQRT2 * _largest(d)
    bound, worst = _SQRT2 * float(_largest(z[None])[0]), 0.0
    for dj in top.tolist():
        bound += dj
        worst = max(worst, bound)
        bound = growth * bound + 1.0
    return worst * 2.0 ** (bits + 1) < 2.0 ** 52 and worst * growth < 2.0 ** (49 - bits)


def _largest(d: np.ndarray) -> np.ndarray:
    """The largest ``|Re|, |Im|`` per leading index (0 if empty)."""
    c = np.ascontiguousarray(d).view(np.float64).reshape(d.shape[0], -1)
    if c.shape[1] == 0:
        return np.zeros(d.shape[0])
    return np.maximum(c.max(axis=1), -c.min(axis=1))


def _replay_steps(z, d, s0, params, coefs):
    """The step arithmetic (:func:`rotate`), vectorised over every resonator."""
    dt = np.int64 if params.integer else np.float64
    one = 2.0 ** params.coef_bits
    a, a_end = ((np.rint(c.real * one).astype(dt), np.rint(c.imag * one).astype(dt))
                if c is not None else None for c in coefs)
    x, y = np.rint(z.real).astype(dt), np.rint(z.imag).astype(dt)
    for j in range(d.shape[0]):
        c, s = a_end if params.at_block_end(s0 + j) else a
        x, y = rotate(x + d[j].real.astype(dt), y + d[j].imag.astype(dt), c, s,
                      params.coef_bits, params.integer)
    return x + 1j * y


def _project(z: np.ndarray, dtype) -> np.ndarray:
    """Compartment membranes ``(Re, −Re, Im, −Im)`` per resonator, flat."""
    out = np.empty((*z.shape, 2, 2), dtype)  # (Re, Im) × (+, −): the compartments' order
    pairs = np.ascontiguousarray(z).reshape(-1).view(np.float64).reshape(*z.shape, 2)
    np.copyto(out[..., 0], pairs, casting="unsafe")  # (whole values: exact in int64)
    np.negative(out[..., 0], out=out[..., 1])
    return out.reshape(-1)
