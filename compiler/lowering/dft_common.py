r"""What every spiking DFT motif shares: weights, part axes, axis bookkeeping, the RMSE protocol.

A spiking DFT (rate-coded, time-coded or radix-4) multiplies the values along
one axis by a complex matrix :math:`W` of shape ``(n_out, n_in)`` — the exact
:func:`radar.dsp.dft_matrix` rows, times a window folded in by the
``fuse-linear`` pass — and is shared over every other (*repetition*) axis.
Neurons are real, so complex values live on a trailing ``part`` axis
(:data:`compiler.snn.PART_AXIS`); a value is a real-linear combination of its
parts and every output part is a real-linear functional of the output:

.. math::

    x = \sum_p c_p\, x_p, \qquad y_q = \mathrm{Re}(d_q\, y), \qquad
    M[(l, p), (k, q)] = \mathrm{Re}(d_q\, W_{kl}\, c_p)

with ``c = (1)`` for ``none``, ``(1, i)`` for ``re_im``, ``(1, -1)`` for
``signed`` and ``(1, -1, i, -i)`` for ``re_im_signed`` (:data:`PART_IN`), and
``d = (1)``, ``(1, -i)``, ``(1, -1)``, ``(1, -1, -i, i)`` (:data:`PART_OUT`:
Re, Im, −Re, −Im).  So ``M`` (:func:`real_weights`) maps the flattened
``(axis, part)`` source to the flattened ``(out_axis, part)`` target of a
:class:`compiler.snn.MatrixProjection`, and :func:`compiler.snn.combine_parts`
reads the output back.

Examples
--------
>>> import numpy as np
>>> w = np.array([[1.0 + 2.0j]])
>>> real_weights(w, "re_im", "re_im").tolist()  # (1+2i)(a+ib) = (a-2b) + i(2a+b)
[[1.0, 2.0], [-2.0, 1.0]]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from compiler.snn import N_PARTS, PART_AXIS, PartLayout
from ir.errors import CompileError
from ir.ops import DFT, Linear, Op, Window
from ir.types import TensorType

__all__ = [
    "PART_IN",
    "PART_OUT",
    "DftAxes",
    "dft_axes",
    "op_weights",
    "real_weights",
    "sft_rmse",
    "modulus_rmse",
]

#: Input coefficients ``c_p``: a split value is ``x = Σ_p c_p·x_p``.
PART_IN: dict[str, tuple[complex, ...]] = {
    "none": (1.0,), "re_im": (1.0, 1j), "signed": (1.0, -1.0), "re_im_signed": (1.0, -1.0, 1j, -1j),
}
#: Output functionals ``d_q``: output part ``q`` carries ``Re(d_q·y)`` (Re, Im, −Re, −Im).
PART_OUT: dict[str, tuple[complex, ...]] = {
    "none": (1.0,), "re_im": (1.0, -1j), "signed": (1.0, -1.0),
    "re_im_signed": (1.0, -1.0, -1j, 1j),
}


@dataclass(frozen=True)
class DftAxes:
    """Axis bookkeeping of one linear-along-an-axis node (``dft`` or ``linear``).

    Parameters
    ----------
    axis, out_axis : str
        The input axis (contracted) and the output axis (produced, same position).
    n_in, n_out : int
        Their sizes.
    repeat : dict of str to int
        The repetition axes (all others) in IR order, shared by one weight copy.
    complex_in : bool
        Whether the input value is complex.
    """

    axis: str
    out_axis: str
    n_in: int
    n_out: int
    repeat: dict[str, int]
    complex_in: bool

    def contract(self, split: PartLayout) -> tuple[str, ...]:
        """Source axes the matrix projection contracts for an input ``split``."""
        return (self.axis, PART_AXIS) if N_PARTS[split] else (self.axis,)

    def produce(self, split: PartLayout) -> tuple[str, ...]:
        """Target axes produced for an output ``split``."""
        return (self.out_axis, PART_AXIS) if N_PARTS[split] else (self.out_axis,)

    def out_shape(self, out_type: TensorType, split: PartLayout) -> dict[str, int]:
        """The output population's shape: the IR output axes, plus ``part`` if split."""
        shape = dict(out_type.axes)
        if N_PARTS[split]:
            shape[PART_AXIS] = N_PARTS[split]
        return shape


def dft_axes(node: str, op: DFT | Linear | Window, in_type: TensorType) -> DftAxes:
    """The :class:`DftAxes` of node ``node`` applying ``op`` to a value of type ``in_type``.

    Examples
    --------
    >>> t = TensorType(axes={"chirp": 4, "sample": 8})
    >>> a = dft_axes("rng", DFT(axis="sample", out_axis="range", keep="positive"), t)
    >>> a.n_in, a.n_out, a.repeat, a.contract("none"), a.produce("re_im")
    (8, 4, {'chirp': 4}, ('sample',), ('range', 'part'))
    """
    out = op.infer(node, [in_type])
    out_axis = getattr(op, "out_axis", None) or op.axis
    repeat = {a: n for a, n in in_type.axes.items() if a != op.axis}
    return DftAxes(axis=op.axis, out_axis=out_axis, n_in=in_type.axes[op.axis],
                   n_out=out.axes[out_axis], repeat=repeat, complex_in=in_type.complex)


def op_weights(op: Op, n_in: int, *, node: str = "") -> np.ndarray:
    r"""The complex matrix ``W`` (``n_out × n_in``) a ``dft``, ``linear`` or ``window`` applies.

    The op's own matrix (``Op.linear_map``): for ``dft``,
    :func:`radar.dsp.dft_matrix` rows (``n_fft``, ``keep``, ``shift``) times the
    folded window, ``W[k, l] = w[l]·e^{-2πi k_k l/N_fft}``; for ``linear``,
    ``matrix + 1j·matrix_imag``; for ``window``, ``diag(w)``.

    Parameters
    ----------
    op : DFT, Linear or Window
        The node's op.
    n_in : int
        Size of its input axis.
    node : str
        Node id for error messages.

    Returns
    -------
    ndarray of complex128, shape (n_out, n_in)

    Raises
    ------
    CompileError
        For an op that is not ``dft`` or ``linear``.

    Examples
    --------
    >>> (op_weights(DFT(axis="s", keep="positive"), 4).round(12) + 0).tolist()
    [[(1+0j), (1+0j), (1+0j), (1+0j)], [(1+0j), -1j, (-1+0j), 1j]]
    >>> op_weights(DFT(axis="s", window="hann"), 3)[0].real.tolist()
    [0.0, 1.0, 0.0]
    """
    w = op.linear_map(n_in)
    if w is not None:
        return w
    raise CompileError(f"node {node!r}: op {op.op!r} has no weight matrix; spiking linear "
                       "motifs lower 'dft', 'linear' and 'window' only", node=node or None)


def real_weights(w: np.ndarray, in_split: PartLayout, out_split: PartLayout) -> np.ndarray:
    r"""The real ``(n_in·P_in, n_out·P_out)`` matrix ``M`` of the module docstring.

    Rows are the source ``(axis, part)`` flattened row-major, columns the target
    ``(out_axis, part)``; without a split the ``part`` axis is absent (``P = 1``).

    Parameters
    ----------
    w : ndarray, shape (n_out, n_in)
        Complex (or real) weights, ``y = W x``.
    in_split, out_split : {"none", "re_im", "signed", "re_im_signed"}
        How the input and output values are spread over parts.

    Returns
    -------
    ndarray of float64

    Examples
    --------
    Real input, output (Re, Im) of the 2-point DFT:

    >>> real_weights(np.array([[1, 1], [1, -1]], complex), "none", "re_im").tolist()
    [[1.0, 0.0, 1.0, 0.0], [1.0, 0.0, -1.0, 0.0]]

    Notes
    -----
    With ``out_split="re_im"`` and ``in_split="re_im"`` this is the complex product:
    ``Re y = A Re x − B Im x``, ``Im y = B Re x + A Im x`` for ``W = A + iB``.
    """
    w = np.asarray(w, dtype=np.complex128)
    c = np.asarray(PART_IN[in_split])
    d = np.asarray(PART_OUT[out_split])
    m = np.real(w.T[:, None, :, None] * c[None, :, None, None] * d[None, None, None, :])
    n_out, n_in = w.shape
    return np.ascontiguousarray(m.reshape(n_in * c.size, n_out * d.size))


def _crop(y: np.ndarray, n_fft: int | None) -> np.ndarray:
    y = np.asarray(y)
    n = y.shape[-1] if n_fft is None else int(n_fft)
    if n // 2 < 2 or y.shape[-1] < n // 2:
        raise CompileError(f"RMSE protocol: need bins 1..{n // 2 - 1} of an {n}-point DFT, the "
                           f"last axis has {y.shape[-1]} bins; pass n_fft for a positive half")
    return y[..., 1:n // 2]


def sft_rmse(y: np.ndarray, ref: np.ndarray, *, n_fft: int | None = None) -> float:
    r"""The S-FT accuracy protocol (López-Randulfe et al. 2022), averaged over the leading axes.

    For each row (last axis = DFT bins from bin 0): keep bins ``1 … n_fft/2 − 1``,
    stack Re and Im, min–max normalise each of ``y`` and ``ref`` jointly over
    both, and take the RMSE of the difference; return the mean over rows.

    .. math:: \mathrm{RMSE} = \sqrt{\tfrac{1}{2K}\sum_k
              (\hat y_k - \widehat{\mathrm{ref}}_k)^2}, \quad
              \hat z = \frac{z - \min z}{\max z - \min z}

    Parameters
    ----------
    y, ref : ndarray of complex
        Same shape ``(..., n_bins)``.
    n_fft : int, optional
        DFT length (default: ``n_bins``); pass ``2·n_bins`` for a ``positive`` half.

    Returns
    -------
    float

    Raises
    ------
    CompileError
        If the shapes differ or there are too few bins.

    Examples
    --------
    >>> ref = np.fft.fft(np.arange(8.0) ** 2)
    >>> sft_rmse(ref, ref), round(sft_rmse(3.0 * ref, ref), 12)
    (0.0, 0.0)
    >>> round(sft_rmse(ref * np.r_[1, 1, 1, 0.5, 1, 1, 1, 1], ref), 4)
    0.0572
    """
    if np.shape(y) != np.shape(ref):
        raise CompileError(f"RMSE protocol: shapes differ, {np.shape(y)} vs {np.shape(ref)}")

    def norm(z: np.ndarray) -> np.ndarray:
        parts = np.concatenate([z.real, z.imag], axis=-1)
        lo = parts.min(axis=-1, keepdims=True)
        span = parts.max(axis=-1, keepdims=True) - lo
        return (parts - lo) / np.where(span > 0, span, 1.0)

    a, b = norm(_crop(y, n_fft)), norm(_crop(ref, n_fft))
    return float(np.mean(np.sqrt(np.mean((a - b) ** 2, axis=-1))))


def modulus_rmse(y: np.ndarray, ref: np.ndarray, *, drop_bin0: bool = True) -> float:
    r"""RMSE of moduli, each min–max normalised to [0, 1] over all entries.

    Parameters
    ----------
    y, ref : ndarray
        Complex values (or already moduli), same shape; the last axis is the bins.
    drop_bin0 : bool
        Drop bin 0 of the last axis first (the papers' protocol).

    Returns
    -------
    float

    Examples
    --------
    >>> modulus_rmse(np.array([0, 1, 3.0]), np.array([0, 2, 6.0]))
    0.0
    """
    def norm(z: np.ndarray) -> np.ndarray:
        m = np.abs(np.asarray(z))
        m = m[..., 1:] if drop_bin0 else m
        span = m.max() - m.min()
        return (m - m.min()) / (span if span > 0 else 1.0)

    if np.shape(y) != np.shape(ref):
        raise CompileError(f"RMSE protocol: shapes differ, {np.shape(y)} vs {np.shape(ref)}")
    return float(np.sqrt(np.mean((norm(y) - norm(ref)) ** 2)))
