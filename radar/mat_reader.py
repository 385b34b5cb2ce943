"""MATLAB ``.mat`` files (v4 to v7), read without trusting a size they declare.

Variables are listed with :func:`scipy.io.whosmat` and only numeric or logical ones are
loaded (structs, cells, objects, strings and sparse matrices are refused). scipy trusts
the byte counts inside a v5/v7 variable: a 4 MB file declaring a 1 × 1 double whose
compressed data element inflates to 4 GiB made it inflate all of it. So scipy never sees
the file itself here. Each top-level element of a v5 file is listed from at most
:data:`MAT_HEADER_BYTES` of it (inflated with a ``max_length``), and the one variable
asked for is inflated (or read) into memory up to what its listed shape and class can
hold plus :data:`MAT_ELEMENT_OVERHEAD_BYTES`; more is refused before scipy parses it. v4
files are never compressed: a variable must fit in the file.
"""

from __future__ import annotations

import io
import os
import struct
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import BinaryIO

import numpy as np

from ir.errors import RadarConfigError
from radar.files import MAX_ARRAY_BYTES, check_frame_shape, open_regular, pick

__all__ = ["MAT_ELEMENT_OVERHEAD_BYTES", "MAT_HEADER_BYTES", "MAT_NUMERIC_CLASSES",
           "MAX_MAT_VARIABLES", "read_mat_array"]

#: MATLAB classes :func:`read_mat_array` loads -> bytes per real element.
MAT_NUMERIC_CLASSES = {"double": 8, "single": 4, "int8": 1, "uint8": 1, "int16": 2,
                       "uint16": 2, "int32": 4, "uint32": 4, "int64": 8, "uint64": 8,
                       "logical": 1}
#: Bytes of each v5 variable inflated (or read) to list it: its tag, flags, dimensions, name.
MAT_HEADER_BYTES = 4096
#: Bytes a v5 variable may hold besides its data (tags, flags, dimensions, name, padding).
MAT_ELEMENT_OVERHEAD_BYTES = 4096
#: Most variables (top-level elements) a v5 file may hold.
MAX_MAT_VARIABLES = 4096

_FILE_HEADER_BYTES = 128
_MI_COMPRESSED = 15
_PIECE_BYTES = 1 << 16  # compressed bytes fed to zlib at a time


def read_mat_array(path: str | Path, name: str | None = None, *, vector_1d: bool = True,
                   max_bytes: int = MAX_ARRAY_BYTES,
                   frame_shape: Sequence[int] | None = None) -> np.ndarray:
    """One numeric variable of a MATLAB ``.mat`` file (v4 to v7, via :func:`scipy.io.loadmat`).

    Parameters
    ----------
    path : str or Path
        The file.
    name : str, optional
        The variable; default: the file's only variable.
    vector_1d : bool
        MATLAB has no 1-D arrays: read a 1 x n or n x 1 variable as shape ``(n,)``
        (default); False keeps MATLAB's 2-D shape.
    max_bytes : int
        Most bytes the variable may take (complex counted twice).
    frame_shape : sequence of int, optional
        One frame of the port the variable is for: its shape (after the 1-D rule) must
        be this or ``(frames, *frame_shape)``, checked before its data is read.

    Returns
    -------
    numpy.ndarray
        The variable in MATLAB's index order (at least 2-D, except vectors as above),
        logical as uint8, complex as complex.

    Raises
    ------
    RadarConfigError
        The file is missing, not a regular file or not a readable ``.mat`` (v7.3 files are
        HDF5: save with ``-v7``); ``name`` is not in it, is in it twice, or is omitted
        while it holds several variables (the message lists them); the variable is not a
        numeric or logical array (a struct, cell, object, string or sparse matrix), over
        ``max_bytes``, of a shape the port does not take, or holds (inflated) more bytes
        than its shape and class need, or a v5 file holds more than
        :data:`MAX_MAT_VARIABLES` variables.

    Examples
    --------
    >>> import tempfile
    >>> from scipy.io import savemat
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     savemat(Path(tmp) / "cube.mat", {"adc": np.arange(6.0).reshape(2, 3)},
    ...             do_compression=True)
    ...     adc = read_mat_array(Path(tmp) / "cube.mat")
    >>> adc.shape, float(adc[1, 2])
    ((2, 3), 5.0)
    """
    path = Path(path)
    with open_regular(path, str(path)) as f:
        head = f.read(_FILE_HEADER_BYTES)
        size = os.fstat(f.fileno()).st_size
        v5 = _is_v5(head)
        if v5:
            elements = _elements(f, size, head, path)
            listing = io.BytesIO()
            listing.write(head)
            for element in elements:
                _copy_element(f, element, head, listing, MAT_HEADER_BYTES, path, None)
            listing.seek(0)
        variables = _variables(listing if v5 else f, path)
        names = [n for n, _, _ in variables]
        var = pick(path, names, name, "variable", "name=VAR; on the command line FILE.mat:VAR")
        if names.count(var) > 1:
            raise RadarConfigError(f"{path}: variable {var!r} is in the file {names.count(var)} "
                                   "times; save it once")
        index = names.index(var)
        _, shape, cls = variables[index]
        need = _check_variable(path, var, shape, cls, max_bytes, vector_1d, frame_shape)
        if v5:
            source = io.BytesIO()
            source.write(head)
            bound = need + MAT_ELEMENT_OVERHEAD_BYTES
            _copy_element(f, elements[index], head, source, bound, path,
                          f"variable {var!r} ({'x'.join(map(str, shape))} {cls}, {need} bytes "
                          "of data at most)")
            source.seek(0)
        else:  # v4: uncompressed, so its data must be in the file
            real = int(np.prod(shape, dtype=object)) * MAT_NUMERIC_CLASSES[cls]
            if real > size:
                raise RadarConfigError(f"{path}: variable {var!r} ({'x'.join(map(str, shape))} "
                                       f"{cls}) needs {real} bytes but the file holds {size}; "
                                       "the file is damaged or truncated, save it again")
            f.seek(0)
            source = f
        array = _load(source, var, path)
    if vector_1d and array.ndim == 2 and 1 in array.shape:
        return array.reshape(-1)
    return array


def _is_v5(head: bytes) -> bool:
    """A v5/v7 header (scipy's test: no zero in bytes 0-3, major version 1 at 124-127)."""
    if len(head) < _FILE_HEADER_BYTES or 0 in head[:4]:
        return False
    tail = head[124:128]
    return tail[tail[2] == ord("I")] == 1


def _endian(head: bytes) -> str:
    return "<" if head[126:128] == b"IM" else ">"


def _elements(f: BinaryIO, size: int, head: bytes, path: Path) -> list[tuple[int, int, int]]:
    """``(offset of data, type, byte count)`` of each top-level element, from the tags only."""
    elements, offset, fmt = [], _FILE_HEADER_BYTES, _endian(head) + "II"
    while offset + 8 <= size:
        if len(elements) == MAX_MAT_VARIABLES:
            raise RadarConfigError(f"{path}: more than {MAX_MAT_VARIABLES} variables "
                                   "(MAX_MAT_VARIABLES); save fewer per file")
        f.seek(offset)
        mdtype, nbytes = struct.unpack(fmt, f.read(8))
        elements.append((offset + 8, mdtype, nbytes))
        offset += 8 + nbytes
    return elements


def _copy_element(f: BinaryIO, element: tuple[int, int, int], head: bytes, out: BinaryIO,
                  bound: int, path: Path, full: str | None) -> None:
    """Write ``element`` uncompressed to ``out``, at most ``bound`` bytes of it.

    ``full`` is None to list (the element cut to ``bound`` bytes, its tag saying so), or
    what the variable is, to read it whole: more than ``bound`` bytes is then refused.
    """
    start, mdtype, nbytes = element
    fmt = _endian(head) + "II"
    f.seek(start)
    if full is None:  # a few KiB: cut and re-tag so that scipy's listing skips to the next
        cut = io.BytesIO()
        if mdtype == _MI_COMPRESSED:
            _inflate(f, nbytes, bound, cut, path)
        else:
            cut.write(struct.pack(fmt, mdtype, nbytes) + f.read(min(nbytes, bound)))
        body = cut.getvalue()[:bound]
        if len(body) >= 8:
            body = struct.pack(fmt, struct.unpack(fmt, body[:8])[0], len(body) - 8) + body[8:]
        out.write(body)
        return
    if mdtype == _MI_COMPRESSED:
        if _inflate(f, nbytes, bound, out, path) > bound:
            raise RadarConfigError(f"{path}: {full} inflates to more than {bound} bytes, more "
                                   "than its shape and class can take; the file is damaged or "
                                   "forged (a deflate bomb), save it again")
        return
    if nbytes > bound:
        raise RadarConfigError(f"{path}: {full} holds a data element of {nbytes} bytes, over "
                               f"the {bound} its shape and class can take; the file is damaged "
                               "or forged, save it again")
    out.write(struct.pack(fmt, mdtype, nbytes))
    out.write(f.read(nbytes))  # at most bound bytes, and no more than the file holds


def _inflate(f: BinaryIO, n_compressed: int, bound: int, out: BinaryIO, path: Path) -> int:
    """Inflate the zlib stream of ``n_compressed`` bytes at ``f`` into ``out``, stopping
    after ``bound + 1`` bytes; the number of bytes written."""
    d, have, left, pending = zlib.decompressobj(), 0, n_compressed, b""
    try:
        while have <= bound and not d.eof:
            if not pending:
                pending = f.read(min(left, _PIECE_BYTES)) if left > 0 else b""
                left -= len(pending)
                if not pending:
                    break
            part = d.decompress(pending, bound + 1 - have)
            pending = d.unconsumed_tail
            out.write(part)
            have += len(part)
    except zlib.error as err:
        raise RadarConfigError(f"{path}: a compressed variable cannot be inflated ({err}); the "
                               "file is damaged, save it again") from None
    return have


def _variables(source: BinaryIO, path: Path) -> list[tuple[str, tuple, str]]:
    from scipy.io import whosmat

    try:
        return [(n, tuple(shape), cls) for n, shape, cls in whosmat(source)]
    except Exception as err:  # scipy raises MatReadError, IndexError, ValueError… on damage
        raise RadarConfigError(f"{path}: not a readable .mat file ({type(err).__name__}: "
                               f"{err}); scipy reads MATLAB v4 to v7 files: save with "
                               "save(..., '-v7')") from None


def _check_variable(path: Path, var: str, shape: tuple, cls: str, max_bytes: int,
                    vector_1d: bool, frame_shape: Sequence[int] | None) -> int:
    """The most bytes ``var`` may take (complex counted twice), after its checks."""
    if cls not in MAT_NUMERIC_CLASSES:
        raise RadarConfigError(f"{path}: variable {var!r} is a MATLAB {cls}, not a numeric "
                               f"array; refused (radarsnn reads {', '.join(MAT_NUMERIC_CLASSES)}"
                               " arrays): save the numbers themselves")
    need = 2 * int(np.prod(shape, dtype=object)) * MAT_NUMERIC_CLASSES[cls]
    if need > max_bytes:
        raise RadarConfigError(f"{path}: variable {var!r} ({'x'.join(map(str, shape))} {cls}) "
                               f"may take {need} bytes, over the limit of {max_bytes} bytes; "
                               "save fewer frames per file")
    read_shape = shape
    if vector_1d and len(shape) == 2 and 1 in shape:
        read_shape = (int(np.prod(shape)),)
    check_frame_shape(f"{path}: variable {var!r}", read_shape, frame_shape)
    return need


def _load(source: BinaryIO, var: str, path: Path) -> np.ndarray:
    from scipy.io import loadmat

    try:
        array = loadmat(source, variable_names=[var])[var]
    except Exception as err:  # as above: any failure of scipy's parser is a damaged file
        raise RadarConfigError(f"{path}: variable {var!r} cannot be read ({type(err).__name__}"
                               f": {err}); save the file again") from None
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "biufc":
        raise RadarConfigError(f"{path}: variable {var!r} is not a numeric array; refused")
    return array
