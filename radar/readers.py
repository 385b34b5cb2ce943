"""Arrays in the files radar users have on disk: ``.npz`` archives and MATLAB ``.mat`` files.

Raw TI captures (``.bin``) are read by :mod:`radar.ti_capture`. Loading never runs code:
``.npz`` members are read with ``allow_pickle=False`` after their header is checked against
the member's bytes (object dtypes refused, a forged shape cannot make numpy allocate more
than the member holds); ``.mat`` variables are listed with :func:`scipy.io.whosmat` first and
only numeric or logical ones are loaded (structs, cells, objects, strings and sparse matrices
are refused). Every error is a :class:`ir.errors.RadarConfigError` naming the file.
"""

from __future__ import annotations

import tokenize
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ir.errors import RadarConfigError

__all__ = ["MAX_ARRAY_BYTES", "MAT_NUMERIC_CLASSES", "read_mat_array", "read_npz_array"]

#: Most bytes one array read from a ``.npz`` or ``.mat`` file may take: 4 GiB.
MAX_ARRAY_BYTES = 4 << 30

#: MATLAB classes :func:`read_mat_array` loads -> bytes per real element.
MAT_NUMERIC_CLASSES = {"double": 8, "single": 4, "int8": 1, "uint8": 1, "int16": 2,
                       "uint16": 2, "int32": 4, "uint32": 4, "int64": 8, "uint64": 8,
                       "logical": 1}

_DAMAGE = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, NotImplementedError,
           RuntimeError, ValueError, OSError, EOFError, KeyError, SyntaxError, IndexError,
           tokenize.TokenError, TypeError, OverflowError, MemoryError)


def _pick(path: Path, names: list[str], key: str | None, kind: str, how: str) -> str:
    """The one name asked for (or the only one), else an error listing the names."""
    listed = ", ".join(repr(n) for n in names) or "none"
    if key is None:
        if len(names) == 1:
            return names[0]
        raise RadarConfigError(f"{path} holds {len(names)} {kind}s ({listed}); name the one to "
                               f"read ({how})")
    if key not in names:
        raise RadarConfigError(f"{path} has no {kind} {key!r}; its {kind}s are {listed}")
    return key


def read_npz_array(path: str | Path, key: str | None = None, *,
                   max_bytes: int = MAX_ARRAY_BYTES) -> np.ndarray:
    """One array of a ``.npz`` archive (``np.savez``, or ``radarsnn run -o``), without pickle.

    Parameters
    ----------
    path : str or Path
        The archive.
    key : str, optional
        The array's name; default: the archive's only array.
    max_bytes : int
        Most bytes the array may declare.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    RadarConfigError
        The file is missing or not a readable zip of ``.npy`` members; ``key`` is not in it
        (or is omitted while it holds several arrays: the message lists them); the array is
        an object array, declares more than ``max_bytes``, or its header does not match the
        member's bytes.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     np.savez(Path(tmp) / "out.npz", det=np.eye(2), rd=np.zeros(3))
    ...     det = read_npz_array(Path(tmp) / "out.npz", "det")
    ...     try:
    ...         read_npz_array(Path(tmp) / "out.npz")
    ...     except RadarConfigError as err:
    ...         message = str(err)
    >>> det.tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    >>> print(message.split("out.npz ", 1)[1])
    holds 2 arrays ('det', 'rd'); name the one to read (key=NAME; on the command line FILE.npz:NAME)
    """
    path = Path(path)
    fmt = np.lib.format
    try:
        with zipfile.ZipFile(path) as zf:
            members = {i.filename.removesuffix(".npy"): i for i in zf.infolist()
                       if i.filename.endswith(".npy")}
            name = _pick(path, list(members), key, "array", "key=NAME; on the command line "
                         "FILE.npz:NAME")
            info = members[name]
            with zf.open(info) as f:
                version = fmt.read_magic(f)
                shape, _, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                                   else fmt.read_array_header_2_0(f))
                have = info.file_size - f.tell()
            if dtype.hasobject:
                raise RadarConfigError(f"{path}: array {name!r} is an object array, refused "
                                       "(loading it would unpickle code); save numbers")
            need = int(np.prod(shape, dtype=object)) * dtype.itemsize
            if need > max_bytes:
                raise RadarConfigError(f"{path}: array {name!r} declares {shape} {dtype} "
                                       f"({need} bytes), over the limit of {max_bytes} bytes; "
                                       "save fewer frames per file")
            if need != have:
                raise RadarConfigError(f"{path}: array {name!r} declares {shape} {dtype} "
                                       f"({need} bytes) but its member holds {have} bytes; "
                                       "the file is damaged or truncated, write it again")
            with zf.open(info) as f:
                return fmt.read_array(f, allow_pickle=False)
    except RadarConfigError:
        raise
    except FileNotFoundError:
        raise RadarConfigError(f"{path}: no such file") from None
    except _DAMAGE as err:
        raise RadarConfigError(f"{path}: not a readable .npz archive of arrays "
                               f"({type(err).__name__}: {err}); write it with numpy.savez"
                               ) from None


def read_mat_array(path: str | Path, name: str | None = None, *, vector_1d: bool = True,
                   max_bytes: int = MAX_ARRAY_BYTES) -> np.ndarray:
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

    Returns
    -------
    numpy.ndarray
        The variable in MATLAB's index order (at least 2-D, except vectors as above),
        logical as uint8, complex as complex.

    Raises
    ------
    RadarConfigError
        The file is missing or not a readable ``.mat`` (v7.3 files are HDF5: save with
        ``-v7``); ``name`` is not in it, or is omitted while it holds several variables (the
        message lists them); the variable is not a numeric or logical array (a struct,
        cell, object, string or sparse matrix), or over ``max_bytes``.

    Examples
    --------
    >>> import tempfile
    >>> from scipy.io import savemat
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     savemat(Path(tmp) / "cube.mat", {"adc": np.arange(6.0).reshape(2, 3)})
    ...     adc = read_mat_array(Path(tmp) / "cube.mat")
    >>> adc.shape, float(adc[1, 2])
    ((2, 3), 5.0)
    """
    from scipy.io import loadmat, whosmat

    path = Path(path)
    if not path.is_file():
        raise RadarConfigError(f"{path}: no such file" if not path.exists() else
                               f"{path}: not a regular file")
    try:
        variables = {n: (shape, cls) for n, shape, cls in whosmat(path)}
    except Exception as err:  # scipy raises MatReadError, IndexError, ValueError… on damage
        raise RadarConfigError(f"{path}: not a readable .mat file ({type(err).__name__}: "
                               f"{err}); scipy reads MATLAB v4 to v7 files: save with "
                               "save(..., '-v7')") from None
    var = _pick(path, list(variables), name, "variable", "name=VAR; on the command line "
                "FILE.mat:VAR")
    shape, cls = variables[var]
    if cls not in MAT_NUMERIC_CLASSES:
        raise RadarConfigError(f"{path}: variable {var!r} is a MATLAB {cls}, not a numeric "
                               f"array; refused (radarsnn reads {', '.join(MAT_NUMERIC_CLASSES)}"
                               " arrays): save the numbers themselves")
    need = 2 * int(np.prod(shape, dtype=object)) * MAT_NUMERIC_CLASSES[cls]
    if need > max_bytes:
        raise RadarConfigError(f"{path}: variable {var!r} ({'x'.join(map(str, shape))} {cls}) "
                               f"may take {need} bytes, over the limit of {max_bytes} bytes; "
                               "save fewer frames per file")
    try:
        array = loadmat(path, variable_names=[var])[var]
    except Exception as err:  # as above: any failure of scipy's parser is a damaged file
        raise RadarConfigError(f"{path}: variable {var!r} cannot be read ({type(err).__name__}"
                               f": {err}); save the file again") from None
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "biufc":
        raise RadarConfigError(f"{path}: variable {var!r} is not a numeric array; refused")
    if vector_1d and array.ndim == 2 and 1 in array.shape:
        return array.reshape(-1)
    return array
