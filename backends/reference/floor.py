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

__all__ = ["FloorProduct", "floor_calls", "floor_products"]


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


def floor_calls(products: list[FloorProduct], seed: int = 0) -> dict[str, Callable[[], None]]:
    """``{"floor": run, "floor_core": run}``: each call does all the dense products (or cores).

    The operands are built once, here; a call is the products alone, one after the
    other (what ``radarsnn bench`` times, in turn with the closed form's runs).
    """
    dense = [(_features(p.rows, p.weights.shape[0], p.n_steps, p.weights.dtype, seed + i),
              p.weights) for i, p in enumerate(products)]
    cores = [(_features(p.rows, (p.core if p.core is not None else p.weights).shape[0],
                        p.n_steps, p.weights.dtype, seed + i),
              p.core if p.core is not None else p.weights) for i, p in enumerate(products)]

    def run(pairs) -> Callable[[], None]:
        def products_once() -> None:
            for x, w in pairs:
                x @ w
        return products_once

    return {"floor": run(dense), "floor_core": run(cores)}

