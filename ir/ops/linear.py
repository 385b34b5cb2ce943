"""Linear ops along one axis: ``window``, ``dft``, ``linear`` and ``sum``.

All act on one named axis and leave the other axes (and their order) alone.
``window``, ``dft`` and ``linear`` take ``amplitude`` values (real or complex);
``sum`` also takes ``power`` values (non-coherent integration).  Their reference
implementations delegate to :mod:`radar.dsp` and :mod:`radar.windows`; the calibration
bound of ``window``, ``dft`` and ``linear`` comes from their matrix (:meth:`DFT.linear_map`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
from pydantic import Field, FiniteFloat, PositiveInt, model_validator

from ir.model import Name
from ir.ops.base import Op
from ir.types import TensorType
from radar.dsp import dft, dft_matrix
from radar.windows import apply_window, window_coefficients

__all__ = ["DFT", "Linear", "Sum", "Window", "WindowKind"]

#: :class:`Linear` matrices as arrays, by the op's identity (kept with the op, so its id is
#: not reused): a program evaluates the same op every frame.
_MATRICES: dict[int, tuple[object, np.ndarray]] = {}

WindowKind = Literal["hann", "hamming", "blackman", "rect"]


def _matrix_bound(op: Op, bounds: list[float], types: list[TensorType]) -> float:
    """The bound of ``y = W x``: ``b`` times the largest row sum of ``|Re W| + |Im W|``."""
    w = op.linear_map(types[0].axes[op.axis])
    return float((np.abs(w.real) + np.abs(w.imag)).sum(axis=1).max()) * bounds[0]


class Window(Op):
    r"""Multiply by a window along one axis: :math:`y[n] = w[n]\,x[n]`.

    Parameters
    ----------
    axis : str
        The axis to window (its size N sets the window length).
    kind : {"hann", "hamming", "blackman", "rect"}, default "hann"
        Symmetric windows of length :math:`N` (:func:`radar.windows.window_coefficients`),
        e.g. hann :math:`w[n] = 0.5 - 0.5\cos(2\pi n/(N-1))`, hamming
        :math:`0.54 - 0.46\cos(2\pi n/(N-1))`, blackman
        :math:`0.42 - 0.5\cos(2\pi n/(N-1)) + 0.08\cos(4\pi n/(N-1))`, rect
        :math:`w[n] = 1`; a length-1 window is :math:`[1]`.

    Notes
    -----
    Output type = input type. Input: ``amplitude`` (real or complex).

    Examples
    --------
    >>> t = TensorType(axes={"chirp": 4, "sample": 8})
    >>> Window(axis="sample").infer("win", [t]) == t
    True
    """

    op: Literal["window"] = "window"
    axis: Name
    kind: WindowKind = "hann"

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.axis_index(node_id, t, self.axis)
        self.check_value(node_id, t, ("amplitude",), allow_complex=True)
        return t

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return apply_window(args[0], self.kind, axis=types[0].index(self.axis))

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """Keeps the bound (taps ``|w| <= 1``)."""
        return bounds[0]

    def linear_map(self, n_in: int) -> np.ndarray:
        """``diag(w)``."""
        return np.diag(window_coefficients(self.kind, n_in)).astype(np.complex128)


class DFT(Op):
    r"""Discrete Fourier transform along one axis, zero-padded to ``n_fft`` points.

    .. math:: X[k] = \sum_{n=0}^{N-1} x[n]\, e^{-2\pi i k n / N_\mathrm{fft}},
              \qquad k = 0, \dots, N_\mathrm{fft} - 1

    with :math:`N` the input axis size and :math:`N_\mathrm{fft} \ge N` (no scaling).

    Parameters
    ----------
    axis : str
        The transformed axis.
    out_axis : str, optional
        Name of the frequency axis (default: keep ``axis``'s name); same position.
    n_fft : int, optional
        Number of DFT points (default: the axis size); must be >= the axis size.
    keep : {"all", "positive"}, default "all"
        ``all`` keeps :math:`N_\mathrm{fft}` bins; ``positive`` keeps bins
        :math:`0 \dots N_\mathrm{fft}/2 - 1` (floor), as for real input samples.
    shift : bool, default False
        Apply ``fftshift`` to the kept bins (zero frequency to the middle), as for Doppler.
    window : {"hann", "hamming", "blackman", "rect"}, optional
        A window folded into the transform, :math:`X[k] = \sum_n w[n]\,x[n]\,e^{\dots}`
        (what the ``fuse-linear`` pass writes when it folds a ``window`` node in;
        default: none).

    Notes
    -----
    Output: complex ``amplitude``, the axis resized to :math:`N_\mathrm{fft}` (``all``)
    or :math:`\lfloor N_\mathrm{fft}/2 \rfloor` (``positive``). Input: ``amplitude``.

    Examples
    --------
    >>> t = TensorType(axes={"chirp": 4, "sample": 8})
    >>> DFT(axis="sample", out_axis="range", keep="positive").infer("rng", [t]).axes
    {'chirp': 4, 'range': 4}
    >>> DFT(axis="chirp", n_fft=16).infer("dop", [t]).shape
    (16, 8)
    """

    op: Literal["dft"] = "dft"
    axis: Name
    out_axis: Name | None = None
    n_fft: PositiveInt | None = None
    keep: Literal["all", "positive"] = "all"
    shift: bool = False
    window: WindowKind | None = None

    def n_points(self, size: int) -> int:
        """DFT length for an input axis of ``size`` samples."""
        return size if self.n_fft is None else self.n_fft

    def n_bins(self, size: int) -> int:
        """Number of output bins for an input axis of ``size`` samples."""
        n = self.n_points(size)
        return n if self.keep == "all" else n // 2

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.axis_index(node_id, t, self.axis)
        self.check_value(node_id, t, ("amplitude",), allow_complex=True)
        size = t.axes[self.axis]
        n = self.n_points(size)
        if n < size:
            raise self.fail(
                node_id,
                f"n_fft={n} is smaller than axis {self.axis!r} of size {size}; "
                f"use n_fft >= {size} (zero padding) or drop n_fft",
            )
        if self.n_bins(size) < 1:
            raise self.fail(node_id, "keep='positive' needs n_fft >= 2; got n_fft=1")
        out = self.out_axis or self.axis
        self.check_new_axis(node_id, t, self.axis, out, "out_axis")
        return t.rename_axis(self.axis, out).resize_axis(out, self.n_bins(size)).replace(
            complex=True, domain="amplitude"
        )

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        ax = types[0].index(self.axis)
        x = args[0] if self.window is None else apply_window(args[0], self.window, axis=ax)
        return dft(x, axis=ax, n_fft=self.n_fft, keep=self.keep, shift=self.shift)

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """b times the largest row sum of ``|Re W| + |Im W|`` (``W``: :meth:`linear_map`)."""
        return _matrix_bound(self, bounds, types)

    def linear_map(self, n_in: int) -> np.ndarray:
        r""":func:`radar.dsp.dft_matrix` rows times the folded window,
        ``W[k, l] = w[l]·e^{-2πi k_k l/N_fft}``.

        Examples
        --------
        >>> (DFT(axis="s", keep="positive").linear_map(4).round(12) + 0).tolist()
        [[(1+0j), (1+0j), (1+0j), (1+0j)], [(1+0j), -1j, (-1+0j), 1j]]
        """
        w = dft_matrix(n_in, n_fft=self.n_fft, keep=self.keep, shift=self.shift)
        if self.window is not None:
            w = w * window_coefficients(self.window, n_in)[None, :]
        return w


class Linear(Op):
    r"""A dense linear map along one axis: :math:`y[j] = \sum_i (A[j,i] + i\,B[j,i])\, x[i]`.

    Parameters
    ----------
    axis : str
        The input axis, of size ``n_in``.
    out_axis : str, optional
        Name of the output axis (default: keep ``axis``'s name); same position, size ``n_out``.
    matrix : list of list of float
        :math:`A`, the real part, ``n_out`` rows of ``n_in`` finite numbers.
    matrix_imag : list of list of float, optional
        :math:`B`, the imaginary part, same shape as ``matrix`` (default: zero).

    Notes
    -----
    Output: ``amplitude``, complex if the input is complex or ``matrix_imag`` is given.

    Examples
    --------
    >>> t = TensorType(axes={"rx": 2, "range": 5})
    >>> Linear(axis="rx", out_axis="beam", matrix=[[1, 1], [1, -1], [0, 1]]).infer("bf", [t]).axes
    {'beam': 3, 'range': 5}
    """

    op: Literal["linear"] = "linear"
    axis: Name
    out_axis: Name | None = None
    matrix: tuple[tuple[FiniteFloat, ...], ...] = Field(min_length=1)
    matrix_imag: tuple[tuple[FiniteFloat, ...], ...] | None = None

    @model_validator(mode="after")
    def _rectangular(self) -> Linear:
        widths = {len(row) for row in self.matrix}
        if len(widths) != 1 or 0 in widths:
            raise ValueError(
                f"matrix rows must all have the same length >= 1; got lengths {sorted(widths)}"
            )
        if self.matrix_imag is not None:
            shape_imag = (len(self.matrix_imag), {len(row) for row in self.matrix_imag})
            if shape_imag != (len(self.matrix), widths):
                raise ValueError(
                    f"matrix_imag must have the shape of matrix ({self.n_out} x {self.n_in}); "
                    f"got {shape_imag[0]} rows of lengths {sorted(shape_imag[1])}"
                )
        return self

    @property
    def n_out(self) -> int:
        """Number of rows (output size)."""
        return len(self.matrix)

    @property
    def n_in(self) -> int:
        """Number of columns (input size)."""
        return len(self.matrix[0])

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.axis_index(node_id, t, self.axis)
        self.check_value(node_id, t, ("amplitude",), allow_complex=True)
        if t.axes[self.axis] != self.n_in:
            raise self.fail(
                node_id,
                f"matrix has {self.n_in} columns but axis {self.axis!r} has size "
                f"{t.axes[self.axis]}; the matrix must be n_out x {t.axes[self.axis]}",
            )
        out = self.out_axis or self.axis
        self.check_new_axis(node_id, t, self.axis, out, "out_axis")
        return t.rename_axis(self.axis, out).resize_axis(out, self.n_out).replace(
            complex=t.complex or self.matrix_imag is not None, domain="amplitude"
        )

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        kept = _MATRICES.get(id(self))
        if kept is None or kept[0] is not self:  # the array of the tuples, once per op
            matrix = np.asarray(self.matrix, dtype=np.float64)
            if self.matrix_imag is not None:
                matrix = matrix + 1j * np.asarray(self.matrix_imag, dtype=np.float64)
            matrix.flags.writeable = False
            if len(_MATRICES) >= 64:
                _MATRICES.clear()
            kept = _MATRICES[id(self)] = (self, matrix)
        matrix = kept[1]
        ax = types[0].index(self.axis)
        return np.moveaxis(np.tensordot(matrix, args[0], axes=([1], [ax])), 0, ax)

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """b times the largest row sum of ``|Re W| + |Im W|`` (``W``: :meth:`linear_map`)."""
        return _matrix_bound(self, bounds, types)

    def linear_map(self, n_in: int) -> np.ndarray:
        """``matrix + 1j·matrix_imag``."""
        w = np.asarray(self.matrix, dtype=np.float64).astype(np.complex128)
        if self.matrix_imag is not None:
            w = w + 1j * np.asarray(self.matrix_imag, dtype=np.float64)
        return w


class Sum(Op):
    r"""Sum over one axis and drop it: :math:`y = \sum_i x[i]`.

    Parameters
    ----------
    axis : str
        The axis summed out (not the only axis).

    Notes
    -----
    Output: the input type without ``axis``. Input: ``amplitude`` or ``power``.

    Examples
    --------
    >>> t = TensorType(axes={"rx": 4, "range": 8}, domain="power")
    >>> Sum(axis="rx").infer("rd", [t])
    TensorType(axes={'range': 8}, complex=False, domain='power')
    """

    op: Literal["sum"] = "sum"
    axis: Name

    def infer(self, node_id: str, inputs: Sequence[TensorType]) -> TensorType:
        (t,) = self.expect_inputs(node_id, inputs)
        self.axis_index(node_id, t, self.axis)
        self.check_value(node_id, t, ("amplitude", "power"), allow_complex=True)
        if t.ndim == 1:
            raise self.fail(
                node_id, f"cannot sum out {self.axis!r}: it is the only axis of the input"
            )
        return t.drop_axis(self.axis)

    def evaluate(self, node_id: str, args: list, types: list) -> np.ndarray:
        return args[0].sum(axis=types[0].index(self.axis))

    def bound(self, node_id: str, bounds: list[float], types: list) -> float:
        """The axis length times the bound."""
        return types[0].axes[self.axis] * bounds[0]
