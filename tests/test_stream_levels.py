"""A stream train kept as its levels (backends/reference/stream_levels.py) and the shared
drive computed from them (backends/reference/level_drive.py): equal to what the bit planes
give — counts, first spike steps, raster, and the count table times the weights — and the
factorisation declining every weight matrix it cannot reproduce exactly."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.level_drive import level_current, level_weights
from backends.reference.stream_levels import StreamLevels
from compiler.snn.stream import StreamCode


@settings(max_examples=80, deadline=None)
@given(m=st.integers(0, 700), f=st.integers(1, 2), pre=st.integers(1, 3),
       inner=st.integers(1, 4), bits=st.integers(1, 24), start=st.integers(0, 3),
       density=st.floats(0.0, 1.0), seed=st.integers(0, 2 ** 16))
def test_counts_and_first_steps_are_those_of_the_bit_planes(m, f, pre, inner, bits, start,
                                                            density, seed):
    rng = np.random.default_rng(seed)
    q = rng.integers(0, 1 << bits, (m, f, pre, inner))
    q[rng.random(q.shape) > density] = 0  # sparse columns and never-set bits
    q = q.astype(np.uint16 if bits <= 16 else np.uint32)
    s = StreamLevels(q, bits, start)
    rows, got_start = s.raster()
    want = np.zeros((m, f, pre, bits, inner), bool)
    for b in range(bits):
        want[:, :, :, b, :] = (q >> b) & 1 == 1
    np.testing.assert_array_equal(rows, want.reshape(m, f * pre * bits * inner))
    assert got_start == start
    for stop in (0, start, start + m // 3, start + m, start + m + 5):
        np.testing.assert_array_equal(s.counts_before(stop),
                                      rows[:max(0, stop - start)].sum(axis=0))
    first = np.where(rows.any(axis=0), rows.argmax(axis=0) + start, -1) if m else -np.ones(
        rows.shape[1], np.int64)
    np.testing.assert_array_equal(s.first_steps(), first)



@settings(max_examples=80, deadline=None)
@given(m=st.integers(0, 300), f=st.integers(1, 3), pre=st.integers(1, 3),
       inner=st.integers(1, 4), bits=st.integers(1, 24), start=st.integers(0, 3),
       grouped=st.booleans(), seed=st.integers(0, 2 ** 16))
def test_column_counts_and_synaptic_events_are_those_of_the_bit_planes(m, f, pre, inner, bits,
                                                                       start, grouped, seed):
    rng = np.random.default_rng(seed)
    q = rng.integers(0, 1 << bits, (m, f, pre, inner))
    q[rng.random(q.shape) < 0.3] = 0
    q = q.astype(np.uint16 if bits <= 16 else np.uint32)
    s = StreamLevels(q, bits, start)
    rows = s.raster()[0]
    # synapses per neuron of one frame, (pre, bit, inner): a few profiles over (pre, inner)
    # shared by groups of bits (some all zero), or drawn per neuron
    profiles = rng.integers(0, 50, (rng.integers(1, 6), pre, 1, inner))
    profiles[0] *= rng.integers(0, 2)
    per = profiles[rng.integers(0, len(profiles), bits), :, 0].transpose(1, 0, 2)
    if not grouped:
        per = rng.integers(0, 50, (pre, bits, inner))
    per = per.reshape(-1)
    mask = int(rng.integers(1, 1 << bits))  # the bit neurons of a masked column count
    planes = rows.reshape(m, f, pre, bits, inner)[:, :, :, [c for c in range(bits)
                                                           if mask >> c & 1]]
    np.testing.assert_array_equal(s.column_counts(start + m, mask), planes.sum(axis=(0, 3)))
    for stop in (0, start, start + m // 2, start + m + 2):
        spiked = rows[:max(0, stop - start)].sum(axis=0).reshape(f, pre, bits, inner)
        np.testing.assert_array_equal(s.column_counts(stop), spiked.sum(axis=2))
        want = int(spiked.sum(axis=0).reshape(-1) @ per)
        got = s.synaptic_events(stop, per)
        n_profiles = len({per.reshape(pre, bits, inner)[:, c].tobytes() for c in range(bits)
                          if per.reshape(pre, bits, inner)[:, c].any()})
        if n_profiles <= 4:
            assert got == want
        else:  # more distinct profiles: the per-neuron counts are asked for
            assert got is None
        # the total: from masked counts that split the bits, or one pass
        assert s.total(stop) == int(spiked.sum())
    low = (1 << int(rng.integers(0, bits + 1))) - 1  # a split of the bits into two masks
    for part in (low, ((1 << bits) - 1) & ~low):
        if part:
            s.column_counts(start + m + 7, part)
    assert s.total(start + m + 7) == int(rows.sum())

def test_hand_worked_levels():
    # levels 5 (101b), 2 (010b), 4 (100b) of one neuron column, 3 bits, from step 2
    s = StreamLevels(np.array([5, 2, 4], np.uint16).reshape(3, 1, 1, 1), 3, 2)
    assert s.counts_before(3).tolist() == [1, 0, 1]
    assert s.counts_before(10).tolist() == [1, 1, 2]
    assert s.first_steps().tolist() == [2, 3, 2]
    assert s.column_counts(10).tolist() == [[[4]]]  # 2 + 1 + 1 set bits
    assert s.synaptic_events(10, np.array([2, 2, 2])) == 8
    assert s.synaptic_events(10, np.array([1, 0, 3])) == 1 * 1 + 3 * 2  # bits 0 and 2
    assert s.column_counts(10, 0b101).tolist() == [[[3]]]
    assert s.column_counts(10, 0b010).tolist() == [[[1]]]
    assert s.total(10) == 4  # from the two masked counts (they split the 3 bits)


def test_stream_code_levels_are_the_rows_of_the_bit_planes():
    code = StreamCode(axis="n", length=3, inner=2, bits=4, x_max=15.0, gains=(1.0, 0.5, 2.0))
    x = np.array([[3.0, 15.0, 8.0, 2.0, 1.0, 7.0]])  # (n, inner) = [[3, 15], [8, 2], [1, 7]]
    q = code.level_rows(x)
    assert q.reshape(3, 2).tolist() == [[3, 15], [4, 1], [2, 14]]
    np.testing.assert_array_equal(StreamLevels(q, 4, 0).raster()[0], code.bit_planes(x))


def _layout(n_reps, n_cols, bits, inner, rng):
    """A random slot order of source neurons ``(pre, bit, inner)`` over ``n_reps`` repetitions
    of ``n_cols`` level columns × ``bits`` input columns, in a random column order."""
    pre = n_reps * n_cols // inner
    neuron = np.arange(pre * bits * inner).reshape(pre, bits, inner)
    by_col = neuron.transpose(0, 2, 1).reshape(n_reps, n_cols, bits)  # (rep, c, b)
    perm = rng.permutation(n_cols * bits)
    slots = by_col.reshape(n_reps, -1)[:, perm]  # slot (rep, input column) → neuron
    c_of, b_of = np.divmod(perm, bits)
    return slots.reshape(-1), c_of, b_of


@settings(max_examples=80, deadline=None)
@given(n_reps=st.integers(1, 4), inner=st.integers(1, 3), per=st.integers(1, 2),
       bits=st.integers(1, 12), n_out=st.integers(1, 3), m=st.integers(1, 9),
       frames=st.integers(1, 2), drop=st.integers(0, 4), seed=st.integers(0, 2 ** 16))
def test_level_current_is_the_count_table_times_the_weights(n_reps, inner, per, bits, n_out, m,
                                                            frames, drop, seed):
    rng = np.random.default_rng(seed)
    n_cols = inner * per  # level columns per repetition (whole pre indices)
    order, c_of, b_of = _layout(n_reps, n_cols, bits, inner, rng)
    v = rng.integers(-5, 6, (n_cols, n_out)).astype(np.float64)
    w = v[c_of] * 2.0 ** b_of[:, None]
    w[b_of < drop] = 0.0  # a projection of the upper bits only: masked levels
    q = rng.integers(0, 1 << bits, (m, frames, n_reps * n_cols // inner, inner)).astype(
        np.uint16)
    lw = level_weights(w, order, n_reps, bits, inner)
    assert lw is not None
    raster = StreamLevels(q, bits, 0).raster()[0].reshape(m, frames, -1)
    counts = raster[:, :, order].reshape(-1, w.shape[0]).astype(np.float64)
    for r0, r1 in ((0, m), (m // 2, m)):
        want = counts.reshape(m, -1)[r0:r1].reshape(-1, w.shape[0]) @ w
        np.testing.assert_array_equal(level_current(q, lw, r0, r1, frames), want)


def test_level_weights_decline_what_they_cannot_reproduce():
    bits, inner = 3, 2
    w = np.array([[1.0], [-1.0], [2.0], [-2.0], [4.0], [-4.0]])  # column (b, c): 2^b·(1, −1)
    assert level_weights(w, None, 1, bits, inner) is not None
    assert level_weights(w * 0.75, None, 1, bits, inner) is None  # fractional V
    odd = w.copy()
    odd[4] = 3.0  # bit 2 of column 0 not 4·V
    assert level_weights(odd, None, 1, bits, inner) is None
    big = w * 2.0 ** 50  # (2^B − 1)·Σ|V| past 2^52: the float sums could round
    assert level_weights(big, None, 1, bits, inner) is None
    # slots whose bit differs between repetitions: not one level column per input column
    order = np.array([0, 1, 2, 3, 4, 5, 8, 9, 6, 7, 10, 11])
    assert level_weights(np.tile(w, 1), order, 2, bits, inner) is None


def test_bit_groups_merge_only_when_disjoint_with_the_same_factor():
    bits, inner = 4, 1
    w = 2.0 ** np.arange(bits)[:, None]  # one level column, V = 1
    low, high = w.copy(), w.copy()
    low[2:], high[:2] = 0.0, 0.0
    lw_low, lw_high = (level_weights(x, None, 1, bits, inner) for x in (low, high))
    assert (lw_low.mask.tolist(), lw_high.mask.tolist()) == ([3], [12])
    both = lw_low.merged(lw_high)
    assert both.mask.tolist() == [15] and both.full
    q = np.arange(16, dtype=np.uint16).reshape(16, 1, 1, 1)
    np.testing.assert_array_equal(level_current(q, both, 0, 16, 1),
                                  level_current(q, lw_low, 0, 16, 1)
                                  + level_current(q, lw_high, 0, 16, 1))
    assert lw_low.merged(lw_low) is None  # overlapping bits
    assert lw_low.merged(level_weights(3 * high, None, 1, bits, inner)) is None  # another V


@settings(max_examples=40, deadline=None)
@given(groups=st.integers(1, 3), bits=st.integers(1, 12), m=st.integers(1, 6),
       seed=st.integers(0, 2 ** 16))
def test_folded_product_is_the_folded_compartment_currents(groups, bits, m, seed):
    from backends.reference.resonator_drive import fold

    rng = np.random.default_rng(seed)
    v = rng.integers(-4, 5, (2, 4 * groups)).astype(np.float64)  # 2 columns, compartments last
    w = np.repeat(v, bits, axis=0) * np.tile(2.0 ** np.arange(bits), 2)[:, None]
    order = np.arange(2 * bits).reshape(bits, 2).T.reshape(-1)  # slot (c, b) → neuron (b, c)
    lw = level_weights(w, order, 1, bits, 2)
    assert lw is not None and lw.folded is not None
    q = rng.integers(0, 1 << bits, (m, 1, 1, 2)).astype(np.uint16)
    plain = level_current(q, lw, 0, m, 1).reshape(m, groups, 4)
    folded = level_current(q, lw, 0, m, 1, folded=True).view(np.complex128)
    np.testing.assert_array_equal(folded, fold(plain))
    assert level_weights(w[:, :3], order, 1, bits, 2).folded is None  # not in fours
