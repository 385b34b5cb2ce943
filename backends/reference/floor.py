r"""The closed form's floor: the dense matrix products it must apply, as plain numpy products.

In a *silent* span (input on, spiking off) the closed form turns every
matrix projection into one product of the whole batch, ``X W`` (``X``: one row
per frame and repetition — e.g. ``rx × chirp`` for a range S-FT — holding the
integer arrival features of the inputs; ``W``: the projection's shared
``n_in × n_out`` matrix, :mod:`backends.reference.spans`).  No simulator can
do less, so the bench times exactly those products, with the same ``W`` (the
plan's own array, never copied or tiled) and an ``X`` of the same shape and
integer values, as a plain ``X @ W`` in the plan's arithmetic: float64 (BLAS;
the sums of integers below ``2**53`` are exact, as the closed form's are) or
int64 (numpy's own loop).  ``floor_core`` times the smaller products through
the sign-symmetric cores the closed form actually multiplies
(:mod:`backends.reference.signed_factor`), for reference.

A resonator population (:mod:`backends.reference.resonator_closed`) has no such
product in fixed point: every input step rounds, so a frame needs ``m`` rotations of
every resonator — ``m`` complex multiplies and roundings of the ``(rows, K, P)`` state
(``rows``: frames × repetitions), each unavoidable.  Its floor (:func:`rotation_floors`)
is exactly those rotations, in the closed form's cache-sized row blocks (the same numpy
operations, :func:`~backends.reference.resonator_closed.replay_rows`, in the blocks it
takes on a thread of its own: the fastest on one core) with no drive, read-out or
encoding.  In floating point the span is linear and its floor is the one
product the closed form applies, the drive ``(rows · P) × m`` times the power table
``m × K`` (complex).

Examples
--------
>>> import numpy as np
>>> from backends.reference import build_plan
>>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, NeuronParams, Phase,
...                           Population, SpikingNetwork)
>>> net = SpikingNetwork(name="n", n_steps=8,
...     populations=[Population(id="a", shape={"r": 3, "i": 2}, source=True),
...                  Population(id="b", shape={"r": 3, "o": 4}, params=NeuronParams(
...                      du=0.0, v_th=1.0, reset="fire_once",
...                      phases=(Phase(start_step=0, spiking_on=False),
...                              Phase(start_step=4, bias=1.0, input_on=False))))],
...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
...                                   produce=("o",), weights=np.ones((2, 4)))],
...     encoders=[Encoder(port="x", population="a",
...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
>>> [(p.id, p.shape) for p in floor_products([build_plan(net)])]
[('w', (3, 2, 4))]
>>> sorted(floor_calls(floor_products([build_plan(net)])))  # time them with radarsnn.bench
['floor', 'floor_core']
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from backends.reference.matrix import MatrixDelivery
from backends.reference.plan import SimPlan
from backends.reference.resonator import ResonatorStepParams
from backends.reference.resonator_closed import _BLOCK_ENTRIES, input_layout, replay_rows

__all__ = ["FloorProduct", "RotationFloor", "floor_calls", "floor_products",
           "rotation_floors"]


@dataclass(frozen=True, eq=False)
class FloorProduct:
    """One ``X @ W`` the closed form must do: ``shape = (rows of X, n_in, n_out)``."""

    id: str
    weights: np.ndarray
    core: np.ndarray | None
    rows: int
    n_steps: int

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(rows, n_in, n_out)``."""
        return (self.rows, *self.weights.shape)

    @property
    def multiply_adds(self) -> int:
        """Multiply-adds of the dense product."""
        return self.rows * self.weights.shape[0] * self.weights.shape[1]


def floor_products(plans: list[SimPlan], n_frames: int = 1) -> list[FloorProduct]:
    """The dense whole-batch products of the closed form's silent spans, per plan.

    A matrix projection with dense weights counts once per delay class when its
    target has a silent span (input on, spiking off).
    """
    out = []
    for plan in plans:
        for qid, dl in plan.deliveries.items():
            params = plan.neurons.get(dl.target)
            silent = params is not None and any(s.input_on and not s.spiking_on
                                                for s in getattr(params, "spans", ()))
            if not isinstance(dl, MatrixDelivery) or not silent:
                continue
            for k, w in enumerate(dl.weights):
                if sp.issparse(w):
                    continue
                factor = dl.factors[k] if dl.factors else None
                out.append(FloorProduct(qid, w, None if factor is None else factor.core,
                                        n_frames * dl.n_reps, plan.network.n_steps))
    return out


def _features(rows: int, cols: int, n_steps: int, dtype, seed: int) -> np.ndarray:
    """Integer arrival features in ``[0, n_steps]`` (what the silent stage multiplies)."""
    rng = np.random.default_rng(seed)
    return rng.integers(0, n_steps + 1, size=(rows, cols)).astype(dtype)


@dataclass(frozen=True, eq=False)
class RotationFloor:
    """The rotations of one resonator population per batch: ``n_steps`` input steps of a
    ``(rows, K, P)`` state; ``coef`` is ``a`` per ``(K, P)`` (over ``2^F`` in fixed point)."""

    id: str
    coef: np.ndarray
    rows: int
    n_steps: int
    coef_bits: int

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(rows, K, P, steps)``."""
        return (self.rows, *self.coef.shape, self.n_steps)

    @property
    def multiply_adds(self) -> int:
        """Complex multiplies (one per resonator and step)."""
        return self.rows * self.coef.size * self.n_steps

    def call(self, seed: int = 0) -> Callable[[], None]:
        """One batch's rotations (fixed point) or power-table product (float), operands
        built here, once."""
        rng = np.random.default_rng(seed)
        k, p = self.coef.shape
        if self.coef_bits:  # whole states well inside the exact range (about 2^20)
            z = (rng.integers(-(1 << 20), 1 << 20, (self.rows, k, p))
                 + 1j * rng.integers(-(1 << 20), 1 << 20, (self.rows, k, p)))
            return lambda: replay_rows(z, self.coef, self.n_steps, block_entries=_BLOCK_ENTRIES)
        drive = rng.standard_normal((p, self.rows, self.n_steps)) + 0j
        table = rng.standard_normal((p, self.n_steps, k)) + 0j
        return lambda: np.matmul(drive, table)


def rotation_floors(plans: list[SimPlan], n_frames: int = 1) -> list[RotationFloor]:
    """The rotations of every resonator population with input steps, per plan.

    Examples
    --------
    >>> from compiler.snn import Population, SpikingNetwork
    >>> from compiler.snn.resonator import Phase, ResonatorParams
    >>> from backends.reference import build_plan
    >>> net = SpikingNetwork(name="n", n_steps=6, populations=[
    ...     Population(id="r", shape={"c": 3, "k": 2, "part": 4}, params=ResonatorParams(
    ...         axis="k", cos=(4096.0, 0.0), sin=(0.0, 4096.0), coef_bits=12,
    ...         phases=(Phase(start_step=0, spiking_on=False),
    ...                 Phase(start_step=4, input_on=False))))])
    >>> [(f.id, f.shape) for f in rotation_floors([build_plan(net)], n_frames=2)]
    [('r', (6, 2, 1, 4))]
    >>> floor_calls([], rotations=rotation_floors([build_plan(net)]))["floor"]()
    """
    out = []
    for plan in plans:
        for pid, params in plan.neurons.items():
            if not isinstance(params, ResonatorStepParams):
                continue
            steps = sum(s.stop - s.start for s in params.spans if s.input_on)
            if steps:
                (lead, _, _), (coef, _) = input_layout(plan, pid)
                out.append(RotationFloor(pid, coef, n_frames * lead, steps, params.coef_bits))
    return out


def floor_calls(products: list[FloorProduct], seed: int = 0,
                rotations: list[RotationFloor] = ()) -> dict[str, Callable[[], None]]:
    """``{"floor": run, "floor_core": run}``: each call does all the dense products (or cores)
    and the resonators' ``rotations``.

    The operands are built once, here; a call is the products alone, one after the
    other (what ``radarsnn bench`` times, in turn with the closed form's runs).
    """
    dense = [(_features(p.rows, p.weights.shape[0], p.n_steps, p.weights.dtype, seed + i),
              p.weights) for i, p in enumerate(products)]
    cores = [(_features(p.rows, (p.core if p.core is not None else p.weights).shape[0],
                        p.n_steps, p.weights.dtype, seed + i),
              p.core if p.core is not None else p.weights) for i, p in enumerate(products)]
    turns = [r.call(seed + i) for i, r in enumerate(rotations)]

    def run(pairs) -> Callable[[], None]:
        def products_once() -> None:
            for x, w in pairs:
                x @ w
            for turn in turns:
                turn()
        return products_once

    return {"floor": run(dense), "floor_core": run(cores)}
