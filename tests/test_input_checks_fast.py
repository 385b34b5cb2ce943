"""The input checks' shortcuts decide as the full checks do: a finite sum proves every value
finite (else the per-value mask names the first bad one), and a stream code's largest part at
or below its bound means no value is out of range (else the flags are counted)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.reference.encoding import _check_array, value_shape
from backends.reference.input_range import check_range, out_of_range
from compiler.snn import Encoder, Population, SpikingNetwork
from compiler.snn.stream import StreamCode
from ir.errors import SimulationError

_VALUES = [0.0, -0.0, 1.0, -3.5, 1e308, -1e308, np.inf, -np.inf, np.nan]


def _net(n: int) -> SpikingNetwork:
    code = StreamCode(axis="i", length=n, inner=1, bits=4, x_max=1.0)
    return SpikingNetwork(name="n", n_steps=n + 1,
                          populations=[Population(id="a", shape={"i": n, "bit": 4, "part": 4},
                                                  source=True)],
                          encoders=[Encoder(port="x", population="a", code=code,
                                            split="re_im_signed")])


@settings(max_examples=80, deadline=None)
@given(re=st.lists(st.sampled_from(_VALUES), min_size=3, max_size=3),
       im=st.lists(st.sampled_from(_VALUES), min_size=3, max_size=3),
       dtype=st.sampled_from([np.complex128, np.complex64]))
def test_finite_check_refuses_exactly_the_non_finite(re, im, dtype):
    net = _net(3)
    drawn = np.empty(3, np.complex128)
    drawn.real, drawn.imag = re, im
    x = np.zeros(value_shape(net, "x"), np.complex128)
    x.flat[:3] = drawn
    with np.errstate(over="ignore"):
        x = x.astype(dtype)  # 1e308 overflows to inf in complex64: refused as inf
    if np.isfinite(x).all():  # a sum past the float range (1e308 + 1e308) is still accepted
        got, n = _check_array(net, "x", "re_im_signed", x)
        assert got is x and n is None
    else:
        with pytest.raises(SimulationError, match="NaN or Inf"):
            _check_array(net, "x", "re_im_signed", x)


@settings(max_examples=80, deadline=None)
@given(parts=st.lists(st.floats(0.0, 2.0), min_size=0, max_size=12),
       x_max=st.sampled_from([1.0, 0.75, 1.5]), bits=st.integers(1, 8))
def test_stream_range_shortcut_counts_as_the_flags(parts, x_max, bits):
    code = StreamCode(axis="i", length=1, inner=1, bits=bits, x_max=x_max)
    p = np.array(parts + [0.0] * (-len(parts) % 4)).reshape(1, -1, 4)
    want = int(np.count_nonzero(out_of_range(code, p, 4, 2)))
    got = check_range("x", code, p, n_parts=4, n_steps=2, framed=True, policy="clip")
    assert got == want
    if want:
        with pytest.raises(SimulationError, match="above the encoder's range"):
            check_range("x", code, p, n_parts=4, n_steps=2, framed=True, policy="reject")
