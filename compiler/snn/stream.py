r"""The stream code: one sample per step, its level sent as binary bit-plane spikes.

The resonators of the ``resonator`` motif take their input sample by sample.  A
:class:`StreamCode` maps the index ``n`` of one value axis (``axis``, length ``L``) to
the step ``start_step + n`` and sends each non-negative part value ``z`` as its level

.. math:: q = \mathrm{rint}\big(\min(z, x_{max}) / x_{max} \cdot (2^B - 1)\big)

in binary (after an optional per-index gain ``g_n``, e.g. a window): the source
population has that axis replaced by a ``bit`` axis of ``B`` neurons, and neuron ``b``
spikes at step ``start_step + n`` iff bit ``b`` of ``q`` is set.  A synapse of weight
``2^b·w`` from neuron ``b`` then delivers ``q·w`` in that one step; the value is
``q · x_max / (2^B − 1)``.  ``inner`` is the number of values (parts included) that
follow the streamed axis in memory, so the train can find it.

Examples
--------
>>> import numpy as np
>>> code = StreamCode(axis="sample", length=3, inner=1, bits=2, x_max=3.0)
>>> code.levels(np.array([0.0, 1.2, 9.0])).tolist()
[0, 1, 3]
>>> code.step_of_level
1.0
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import ConfigDict, Field

from ir.errors import NetworkValidationError
from ir.model import CheckedModel

__all__ = ["BIT_AXIS", "StreamCode"]

#: The axis of the bit-plane neurons that replaces the streamed axis in a source population.
BIT_AXIS = "bit"


class StreamCode(CheckedModel):
    """Binary bit-plane stream along one value axis (see the module docstring).

    Parameters
    ----------
    axis : str
        The value axis streamed over time (one index per step).
    length : int
        Its size ``L``.
    inner : int
        Values (parts included) after ``axis`` in memory order.
    bits : int
        Bits ``B`` of the level.
    x_max : float
        The value of the top level ``2^B − 1``.
    start_step : int
        Step of index 0.
    gains : tuple of float
        Optional factor per index of ``axis`` applied before the level (a window the
        sensor interface applies as it streams); empty: none.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    error_class = NetworkValidationError

    type: Literal["stream"] = "stream"
    axis: str
    length: int = Field(ge=1)
    inner: int = Field(ge=1)
    bits: int = Field(ge=1, le=30)
    x_max: float = Field(gt=0)
    x_min: float = 0.0
    start_step: int = Field(default=0, ge=0)
    gains: tuple[float, ...] = ()

    @property
    def step_of_level(self) -> float:
        """The value of one level: ``x_max / (2^B − 1)``."""
        return self.x_max / ((1 << self.bits) - 1)

    def levels(self, parts: np.ndarray) -> np.ndarray:
        """Whole levels ``q`` of non-negative part values (clipped to ``x_max``)."""
        z = np.clip(np.asarray(parts, np.float64), 0.0, self.x_max)
        return np.rint(z / self.step_of_level).astype(np.int64)

    def bound(self) -> float:
        """The largest value that rounds to the top level (above it clipping changes spikes)."""
        return self.x_max + 0.5 * self.step_of_level

    def level_rows(self, parts: np.ndarray) -> np.ndarray:
        """Levels as ``(L, frames, pre, inner)`` unsigned ints from ``(frames, size)`` parts
        (gains applied): row ``n`` is sent at step ``start_step + n``.

        Examples
        --------
        >>> code = StreamCode(axis="n", length=2, inner=1, bits=2, x_max=3.0)
        >>> code.level_rows(np.array([[1.0, 2.0]])).reshape(2).tolist()
        [1, 2]
        """
        f = parts.shape[0]
        z = np.ascontiguousarray(parts, np.float64).reshape(f, -1, self.length, self.inner)
        q = np.empty((self.length, *z.shape[:2], self.inner))  # L, f, pre, in: one buffer
        # the transpose moves whole inner rows: copied as opaque records (memcpy-sized moves,
        # 2x faster than a strided float copy), then the steps of levels() in place
        row = np.dtype((np.void, 8 * self.inner))
        np.copyto(q.view(row)[..., 0], np.moveaxis(z.view(row)[..., 0], 2, 0))
        if self.gains:
            np.multiply(q, np.asarray(self.gains)[:, None, None, None], out=q)
        np.clip(q, 0.0, self.x_max, out=q)
        np.divide(q, self.step_of_level, out=q)
        np.rint(q, out=q)
        return q.astype(np.uint16 if self.bits <= 16 else np.uint32)  # whole, below 2^bits

    def signed_level_rows(self, values: np.ndarray) -> np.ndarray | None:
        r""":meth:`level_rows` of the ``re_im_signed`` parts of complex128 ``values``
        (``(frames, *value_shape)``) without forming the parts; None where this does not apply
        (another dtype, ``inner`` not whole values of four parts, a negative gain).

        With ``y = g_n·c`` per component ``c`` (Re, Im) and a gain ``g_n ≥ 0``, the parts
        ``max(±c, 0)`` have levels ``L(±y)`` with ``L(t) = rint(clip(t, 0, x_max)/Δ)`` —
        ``(−c)·g`` is ``−(c·g)`` exactly — so ``L(|y|)`` goes to the part of ``y``'s sign and
        0 to the other: one level per component instead of one per part, half the float
        passes.

        Examples
        --------
        >>> code = StreamCode(axis="n", length=2, inner=4, bits=2, x_max=3.0)
        >>> code.signed_level_rows(np.array([[1.0 - 2.0j, -3.0 + 0.0j]])).reshape(2, 4).tolist()
        [[1, 0, 0, 2], [0, 3, 0, 0]]
        """
        gains = np.asarray(self.gains, np.float64)
        if (values.dtype != np.complex128 or self.inner % 4 or not values.size
                or (gains < 0).any()):
            return None
        f = values.shape[0]
        comps = np.ascontiguousarray(values).reshape(-1).view(np.float64).reshape(
            f, -1, self.length, self.inner // 4, 2)  # f, pre, L, values, (Re, Im)
        y = np.multiply(comps, gains[:, None, None]) if self.gains else comps
        a = np.abs(y)
        np.clip(a, 0.0, self.x_max, out=a)
        np.divide(a, self.step_of_level, out=a)
        np.rint(a, out=a)
        dt = np.uint16 if self.bits <= 16 else np.uint32
        level = a.astype(dt)
        parts = np.empty((*level.shape, 2), dt)  # (component, sign): Re+, Re−, Im+, Im−
        np.multiply(level, y > 0, out=parts[..., 0])
        np.multiply(level, y < 0, out=parts[..., 1])
        out = np.empty((self.length, f, comps.shape[1], self.inner), dt)  # L, f, pre, inner
        row = np.dtype((np.void, parts.itemsize * self.inner))  # whole inner rows moved
        np.copyto(out.view(row)[..., 0], np.moveaxis(parts.reshape(
            f, -1, self.length, self.inner).view(row)[..., 0], 2, 0))
        return out

    def bit_planes(self, parts: np.ndarray) -> np.ndarray:
        """Spikes as ``(L, frames · pre · B · inner)`` booleans from ``(frames, size)`` parts.

        Examples
        --------
        >>> code = StreamCode(axis="n", length=2, inner=1, bits=2, x_max=3.0)
        >>> code.bit_planes(np.array([[1.0, 2.0]])).astype(int).tolist()
        [[1, 0], [0, 1]]
        """
        q = self.level_rows(parts)
        planes = np.empty((self.length, *q.shape[1:3], self.bits, q.shape[3]), bool)
        bit = np.empty_like(q)
        for b in range(self.bits):  # one plane per bit, written in place: no int64 cube
            np.bitwise_and(q, 1 << b, out=bit)
            np.not_equal(bit, 0, out=planes[:, :, :, b, :])
        return planes.reshape(self.length, -1)
