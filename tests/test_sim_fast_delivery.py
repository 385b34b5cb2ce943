"""The step engine's fast delivery paths against the plain ones, bit for bit.

* ``grouped_sums`` (level-by-level sums of gathered weight rows) must give every
  bit of ``np.add.reduceat`` — the arithmetic the closed form's driven path and the
  emitted numpy code share — for any floats (negative zeros, subnormals, huge
  values), run lengths across numpy's 8-addend pairwise boundary, and scales.
* ``MatrixDelivery.add_to`` must equal ``out + current(...)`` wherever ``out``
  holds no negative zero, for any axis layout (repetitions matched by name, target
  axes permuted), batch, delay class, dense or CSR weights, BLAS or gathering.
* ``TrainCurrents`` (currents of an encoder's train computed many steps per batch)
  must equal the per-step delivery for every step, whatever the block size.
* ``synapses_per_source`` must count what ``n_events`` counts.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.delivery import (
    MatrixDelivery,
    StencilDelivery,
    TrainCurrents,
    add_current,
    synapses_per_source,
)
from backends.reference.row_sums import SEQUENTIAL_MAX, grouped_sums
from compiler.snn import MatrixProjection, Population, StencilProjection


def _bits(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    return a.view(np.int64) if a.dtype == np.float64 else a


def nasty_floats(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Normal numbers over 600 orders of magnitude, with ±0 and subnormals mixed in."""
    x = rng.normal(size=shape) * 10.0 ** rng.integers(-320, 300, size=shape)
    x[rng.random(shape) < 0.1] = 0.0
    x[rng.random(shape) < 0.1] = -0.0
    return x


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_grouped_sums_are_reduceat_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    integer = rng.random() < 0.2
    n_table, n_out = int(rng.integers(1, 12)), int(rng.integers(1, 5))
    lengths = rng.choice([1, 2, 3, SEQUENTIAL_MAX, SEQUENTIAL_MAX + 1, 20],
                         size=int(rng.integers(1, 7)))
    rows = np.repeat(np.sort(rng.choice(100, size=lengths.size, replace=False)), lengths)
    index = rng.integers(0, n_table, size=rows.size)
    if integer:
        table = rng.integers(-(2**40), 2**40, size=(n_table, n_out))
        scale = rng.integers(-5, 6, size=rows.size) if rng.random() < 0.3 else None
    else:
        table = nasty_floats(rng, (n_table, n_out))
        scale = nasty_floats(rng, (rows.size,)) if rng.random() < 0.3 else None
    with np.errstate(all="ignore"):  # inf - inf on purpose
        hit, sums = grouped_sums(table, index, rows, scale)
        starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
        gathered = table[index] if scale is None else table[index] * scale[:, None]
        want = np.add.reduceat(gathered, starts, axis=0)
    order = np.argsort(hit)
    np.testing.assert_array_equal(hit[order], rows[starts])
    np.testing.assert_array_equal(_bits(sums[order]), _bits(want))


def test_grouped_sums_hand_worked() -> None:
    """Rows 4 and 9: 4 gets table rows 0, 2, 2 (1 + (100 + 100)); 9 gets row 1 alone."""
    table = np.array([[1.0, -1.0], [10.0, 0.5], [100.0, 0.25]])
    hit, sums = grouped_sums(table, np.array([0, 2, 2, 1]), np.array([4, 4, 4, 9]))
    assert dict(zip(hit.tolist(), sums.tolist(), strict=True)) == {
        4: [201.0, -0.5], 9: [10.0, 0.5]}


def random_delivery(rng: np.random.Generator, integer: bool):
    """A matrix projection with repetitions, permuted target axes and maybe delays/CSR."""
    src_axes = {"r": int(rng.integers(1, 4)), "i": int(rng.integers(1, 5)),
                "s": int(rng.integers(1, 3))}
    order = rng.permutation(list(src_axes))
    src = Population(id="a", shape={a: src_axes[a] for a in order}, source=True)
    produce = {"o": int(rng.integers(1, 5)), "p": int(rng.integers(1, 3))}
    tgt_axes = {"r": src_axes["r"], "s": src_axes["s"], **produce}
    tgt = Population(id="b", shape={a: tgt_axes[a] for a in rng.permutation(list(tgt_axes))})
    n_in, n_out = src_axes["i"], produce["o"] * produce["p"]
    w = (rng.integers(-9, 10, size=(n_in, n_out)).astype(float) if integer
         else nasty_floats(rng, (n_in, n_out)))
    w[rng.random(w.shape) < 0.3] = 0.0
    delays = rng.integers(0, 3, size=w.shape) if rng.random() < 0.4 else None
    if rng.random() < 0.2:  # COO weights (stored as CSR, like every delayed projection)
        r, c = np.nonzero(w)
        proj = MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                produce=("o", "p"), rows=r, cols=c, values=w[r, c],
                                n_in_out=w.shape, delays=None if delays is None else delays[r, c])
    else:
        proj = MatrixProjection(id="w", source="a", target="b", contract=("i",),
                                produce=("o", "p"), weights=w, delays=delays)
    dl = MatrixDelivery.build(proj, src, tgt, integer)
    if rng.random() < 0.3:
        dl = replace(dl, blas_events=True)
    return dl, src, tgt


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_add_to_equals_adding_the_current(seed: int) -> None:
    rng = np.random.default_rng(seed)
    integer = rng.random() < 0.3
    dl, src, tgt = random_delivery(rng, integer)
    n_batch = int(rng.integers(1, 4))
    events = np.flatnonzero(rng.random(n_batch * src.size) < rng.random())
    for k in range(len(dl.delays)):
        out = (rng.integers(-50, 50, size=n_batch * tgt.size) if integer
               else np.abs(nasty_floats(rng, (n_batch * tgt.size,))))  # no -0.0 in out
        with np.errstate(all="ignore"):  # inf - inf on purpose
            want = out + dl.current(k, events, n_batch).reshape(-1)
            dl.add_to(k, events, n_batch, out)
        np.testing.assert_array_equal(_bits(out), _bits(want))
        counted = int(synapses_per_source(dl, k)[events % src.size].sum())
        assert counted == dl.n_events(k, events)


def test_add_to_hand_worked_transposed_target() -> None:
    """Target axes (o, r) while the block is (r, o): rep 1's outputs land at o·2 + 1."""
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=np.array([[1.0, 2.0, 3.0]]))
    a = Population(id="a", shape={"r": 2, "i": 1}, source=True)
    dl = MatrixDelivery.build(proj, a, Population(id="b", shape={"o": 3, "r": 2}))
    out = np.zeros(6)
    dl.add_to(0, np.array([1]), 1, out)  # source (r=1, i=0)
    assert out.tolist() == [0.0, 1.0, 0.0, 2.0, 0.0, 3.0]


def test_stencil_takes_the_dense_adder() -> None:
    proj = StencilProjection(id="s", source="a", target="b", axes=("r",),
                             kernel=np.array([0.5, 0.0, 0.25]), edge=("wrap",))
    a = Population(id="a", shape={"r": 5}, source=True)
    dl = StencilDelivery.build(proj, a, Population(id="b", shape={"r": 5}))
    out = np.arange(5.0)
    add_current(dl, 0, np.array([0, 3]), 1, out)
    np.testing.assert_array_equal(out, np.arange(5.0) + dl.current(0, np.array([0, 3]), 1)[0])
    assert synapses_per_source(dl, 0).tolist() == [2] * 5


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), block_bytes=st.sampled_from([1, 64, 1 << 20]))
def test_train_currents_equal_step_by_step_delivery(seed: int, block_bytes: int) -> None:
    rng = np.random.default_rng(seed)
    integer = rng.random() < 0.3
    dl, src, _ = random_delivery(rng, integer)
    dl = replace(dl, blas_events=False)
    if not dl.rows_independent:
        assert any(sp.issparse(w) for w in dl.weights)  # CSR (delays, COO) is not batched
        return
    n_frames, n_steps = int(rng.integers(1, 4)), int(rng.integers(1, 12))
    steps = rng.integers(0, n_steps + 2, size=n_frames * src.size)  # some never spike
    flat = np.flatnonzero(steps < n_steps)
    order = np.argsort(steps[flat], kind="stable")
    flat, spike_steps = flat[order], steps[flat][order]
    for k, d in enumerate(dl.delays):
        ahead = TrainCurrents(dl, k, d, flat, spike_steps, n_frames, n_steps, block_bytes)
        for t in range(n_steps):
            events = flat[spike_steps == t - d]
            with np.errstate(all="ignore"):
                got = ahead.at(t)
                hit, part = dl.row_currents(k, events, n_frames) if events.size else (None, None)
            if not events.size:
                assert got is None
                continue
            o = np.argsort(hit)
            np.testing.assert_array_equal(got[0], hit[o])
            np.testing.assert_array_equal(_bits(got[1]), _bits(part[o]))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), block_bytes=st.sampled_from([1, 4096, 1 << 20]))
def test_train_currents_with_long_runs(seed: int, block_bytes: int) -> None:
    """Up to 40 inputs of one repetition spiking in the same step: runs beyond 8 addends."""
    rng = np.random.default_rng(seed)
    n_in, n_out = int(rng.integers(9, 41)), int(rng.integers(1, 4))
    proj = MatrixProjection(id="w", source="a", target="b", contract=("i",), produce=("o",),
                            weights=nasty_floats(rng, (n_in, n_out)))
    src = Population(id="a", shape={"r": 2, "i": n_in}, source=True)
    dl = MatrixDelivery.build(proj, src, Population(id="b", shape={"r": 2, "o": n_out}))
    n_frames, n_steps = 2, 3
    steps = rng.integers(0, n_steps, size=n_frames * src.size)
    order = np.argsort(steps, kind="stable")
    flat, spike_steps = order, steps[order]
    ahead = TrainCurrents(dl, 0, 0, flat, spike_steps, n_frames, n_steps, block_bytes)
    for t in range(n_steps):
        with np.errstate(all="ignore"):
            got = ahead.at(t)
            hit, part = dl.row_currents(0, np.sort(flat[spike_steps == t]), n_frames)
        np.testing.assert_array_equal(got[0], hit)
        np.testing.assert_array_equal(_bits(got[1]), _bits(part))
