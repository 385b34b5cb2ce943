"""Tensor types: ordered named axes with sizes, real or complex, and a value domain.

A value flowing along a graph edge is an n-dimensional array whose dimensions
are named. The order of ``axes`` is the array's dimension order, so
``{"rx": 4, "chirp": 64, "sample": 256}`` is an array of shape ``(4, 64, 256)``
indexed ``x[rx, chirp, sample]``.

The ``domain`` says what the numbers mean:

==========  ====================================================================
amplitude   a linear signal amplitude (raw samples, spectra, ``|X|``); may be complex
power       a squared magnitude ``|X|^2`` (real, non-negative)
db          a logarithmic level in decibels (real)
mask        booleans, e.g. CFAR detections (real)
==========  ====================================================================

Only ``amplitude`` values may be complex.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, PositiveInt, model_validator

from ir.errors import IRError
from ir.model import IRModel, Name

__all__ = ["DOMAINS", "MAX_AXES", "Domain", "TensorType"]

Domain = Literal["amplitude", "power", "db", "mask"]
DOMAINS: tuple[str, ...] = ("amplitude", "power", "db", "mask")

#: Most axes a value may have.  numpy arrays have at most 64 dimensions, and the
#: reference implementations add some: a CFAR's sliding windows double them, the
#: simulator adds a frames axis and a ``part`` axis (2 x 24 + 2 = 50).  A CFAR over 32
#: axes already fails in numpy; radar values need 5 or 6.
MAX_AXES = 24


class TensorType(IRModel):
    """The type of a value on a graph edge.

    Parameters
    ----------
    axes : dict[str, int]
        Axis name -> size, in array dimension order; 1 to :data:`MAX_AXES` axes, sizes >= 1.
    complex : bool, default False
        Whether values are complex. Only the ``amplitude`` domain may be complex.
    domain : {"amplitude", "power", "db", "mask"}, default "amplitude"
        What the numbers mean (see the module docstring).

    Raises
    ------
    IRError
        If an axis size is < 1, an axis name is malformed, there are no axes or more
        than :data:`MAX_AXES`, or a non-amplitude domain is complex.

    Examples
    --------
    >>> t = TensorType(axes={"chirp": 64, "sample": 256}, complex=True)
    >>> t.shape, t.names, t.ndim
    ((64, 256), ('chirp', 'sample'), 2)
    >>> t.rename_axis("sample", "range").resize_axis("range", 128).names
    ('chirp', 'range')
    >>> t.drop_axis("chirp").shape
    (256,)
    >>> t.replace(complex=False, domain="power").domain
    'power'
    """

    axes: dict[Name, PositiveInt] = Field(min_length=1)
    complex: bool = False
    domain: Domain = "amplitude"

    @model_validator(mode="after")
    def _few_enough_axes(self) -> TensorType:
        if len(self.axes) > MAX_AXES:
            raise ValueError(f"{len(self.axes)} axes, over the limit of {MAX_AXES} (MAX_AXES: "
                             "numpy arrays have at most 64 dimensions, and windows and frames "
                             "add some); merge axes")
        return self

    @model_validator(mode="after")
    def _only_amplitude_is_complex(self) -> TensorType:
        if self.complex and self.domain != "amplitude":
            raise ValueError(
                f"domain {self.domain!r} values are real; only 'amplitude' may be complex"
            )
        return self

    @property
    def names(self) -> tuple[str, ...]:
        """Axis names in dimension order."""
        return tuple(self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        """Array shape (axis sizes in dimension order)."""
        return tuple(self.axes.values())

    @property
    def ndim(self) -> int:
        """Number of axes."""
        return len(self.axes)

    @property
    def size(self) -> int:
        """Number of elements (product of the axis sizes).

        Examples
        --------
        >>> TensorType(axes={"a": 3, "b": 4}).size
        12
        """
        total = 1
        for n in self.axes.values():
            total *= n
        return total

    @property
    def nbytes(self) -> int:
        """Bytes of a numpy array of this type: 16 per complex element, 8 per real one, 1 per
        mask element (a Python int: a declared size need not fit in 64 bits).

        Examples
        --------
        >>> TensorType(axes={"a": 3}, complex=True).nbytes, TensorType(axes={"a": 2**62}).nbytes
        (48, 36893488147419103232)
        """
        return self.size * (1 if self.domain == "mask" else 16 if self.complex else 8)

    def index(self, axis: str) -> int:
        """Dimension index of ``axis``.

        Raises
        ------
        IRError
            If there is no such axis; the message lists the available axes.

        Examples
        --------
        >>> TensorType(axes={"chirp": 2, "sample": 8}).index("sample")
        1
        """
        if axis not in self.axes:
            raise IRError(f"unknown axis {axis!r}; available axes: {list(self.axes)}")
        return self.names.index(axis)

    def replace(self, **changes: object) -> TensorType:
        """A validated copy with some fields changed (``axes``, ``complex``, ``domain``)."""
        return TensorType(**{**self.model_dump(), **changes})

    def rename_axis(self, old: str, new: str) -> TensorType:
        """Rename axis ``old`` to ``new`` in place (same position and size).

        Raises
        ------
        IRError
            If ``old`` is unknown or ``new`` names another existing axis.

        Examples
        --------
        >>> TensorType(axes={"a": 2, "b": 3}).rename_axis("a", "c").axes
        {'c': 2, 'b': 3}
        """
        self.index(old)
        if new != old and new in self.axes:
            raise IRError(
                f"cannot rename axis {old!r} to {new!r}: duplicate axis name, "
                f"{new!r} already in {list(self.axes)}"
            )
        return self.replace(axes={(new if k == old else k): v for k, v in self.axes.items()})

    def resize_axis(self, axis: str, size: int) -> TensorType:
        """Change the size of ``axis`` (same position and name)."""
        self.index(axis)
        return self.replace(axes={**self.axes, axis: size})

    def drop_axis(self, axis: str) -> TensorType:
        """Remove ``axis``; the others keep their order.

        Raises
        ------
        IRError
            If ``axis`` is unknown or is the only axis.
        """
        self.index(axis)
        if self.ndim == 1:
            raise IRError(f"cannot drop axis {axis!r}: it is the only axis")
        return self.replace(axes={k: v for k, v in self.axes.items() if k != axis})
