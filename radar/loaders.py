"""Loaders for the real radar captures shipped in ``radar/data`` (see its README.md).

Files are read with :func:`radar.readers.read_npy_array` (no pickle, the header checked
before numpy allocates: at most 16 bytes per expected value): loading never runs code. Every
file is checked for its expected dtype and shape; a missing, truncated or malformed file
raises :class:`ir.errors.RadarConfigError` naming the file and what was expected. The
captures root is ``$RADARSNN_DATA`` or the package's own ``radar/data`` (:func:`default_data_dir`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ir.errors import RadarConfigError
from radar.readers import read_npy_array

__all__ = ["OPENRADAR_CAPTURES", "SHIPPED_DATA_DIR", "default_data_dir", "load_openradar",
           "load_ti_chirps"]

DATA_ENV_VAR = "RADARSNN_DATA"

OPENRADAR_CAPTURES: dict[str, tuple[int, int]] = {
    "simple_frame_1": (128, 128),
    "doppler_example": (128, 256),
}
"""OpenRadar capture name -> (chirps, samples) of its ``.npy`` file."""

_UINT16_SPAN = 65536

SHIPPED_DATA_DIR = Path(__file__).resolve().parent / "data"
"""The captures shipped with the package (``radar/data``: ``ti_chirps/``, ``openradar/``)."""


def default_data_dir() -> Path:
    """The folder of real captures: ``$RADARSNN_DATA`` if set, else the shipped ``radar/data``.

    The shipped folder is package data: an editable and a regular install both hold it (its
    README.md names each capture's origin and licence).

    Returns
    -------
    pathlib.Path
        Not checked for existence; the loaders do that.

    Examples
    --------
    >>> default_data_dir().name
    'data'
    """
    env = os.environ.get(DATA_ENV_VAR)
    if env:
        return Path(env)
    return SHIPPED_DATA_DIR


def _folder(directory: str | Path | None, sub: str) -> Path:
    """``<directory>/<sub>``, or a RadarConfigError saying how to point at the captures."""
    root = Path(directory) if directory is not None else default_data_dir()
    folder = root / sub
    if not folder.is_dir():
        raise RadarConfigError(
            f"capture folder {folder} does not exist; pass directory=<captures root> "
            f"or set the environment variable {DATA_ENV_VAR} to the folder that holds "
            f"'{sub}/'"
        )
    return folder


def _load(path: Path, kind: str, shape: tuple[int, ...]) -> np.ndarray:
    """Load one ``.npy`` file without pickle and check its dtype kind and shape."""
    if not path.is_file():
        raise RadarConfigError(f"capture file {path} is missing; expected a {kind} array "
                               f"of shape {shape}")
    try:  # bounded: at most 16 bytes (complex128) per expected value, declared in the header
        array = read_npy_array(path, max_bytes=16 * int(np.prod(shape)), what=str(path))
    except RadarConfigError as err:
        raise RadarConfigError(
            f"capture file {path} cannot be read as a .npy array ({err}); expected a {kind} "
            f"array of shape {shape}; the file may be truncated or not a .npy file"
        ) from None
    if not isinstance(array, np.ndarray) or array.dtype.kind != kind[0]:
        raise RadarConfigError(
            f"capture file {path} holds dtype {getattr(array, 'dtype', type(array))}, "
            f"expected {kind} (numpy kind '{kind[0]}')"
        )
    if array.shape != shape:
        raise RadarConfigError(
            f"capture file {path} has shape {array.shape}, expected {shape}"
        )
    return array


def load_ti_chirps(directory: str | Path | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Four real TI chirps and their stored range FFT (``ti_chirps/``).

    Parameters
    ----------
    directory : str or Path, optional
        The captures root holding ``ti_chirps/``; default :func:`default_data_dir`.

    Returns
    -------
    chirps : numpy.ndarray
        float64, shape (4, 1024): ADC codes of ``data_tum.npy``.
    fft_reference : numpy.ndarray
        complex128, shape (4, 1024): ``fft_result.npy`` =
        ``np.fft.fft(chirps, axis=1)`` (no window, no scaling), stored in complex64.

    Raises
    ------
    RadarConfigError
        The folder or a file is missing, unreadable, or of the wrong dtype or shape.

    Examples
    --------
    A stand-in folder with a constant chirp (the real one is ``default_data_dir()``):

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     (Path(tmp) / "ti_chirps").mkdir()
    ...     x = np.ones((4, 1024), dtype=np.float32)
    ...     np.save(Path(tmp) / "ti_chirps" / "data_tum.npy", x)
    ...     np.save(Path(tmp) / "ti_chirps" / "fft_result.npy",
    ...             np.fft.fft(x, axis=1).astype(np.complex64))
    ...     chirps, ref = load_ti_chirps(tmp)
    >>> chirps.dtype, ref.dtype, complex(ref[0, 0])
    (dtype('float64'), dtype('complex128'), (1024+0j))
    """
    folder = _folder(directory, "ti_chirps")
    chirps = _load(folder / "data_tum.npy", "float", (4, 1024))
    reference = _load(folder / "fft_result.npy", "complex", (4, 1024))
    return chirps.astype(np.float64), reference.astype(np.complex128)


def load_openradar(name: str = "simple_frame_1",
                   directory: str | Path | None = None) -> np.ndarray:
    """One OpenRadar capture (``openradar/<name>.npy``), decoded to signed ADC codes.

    The file stores raw unsigned 16-bit codes ``v`` in 0..65535 as floats in both the real
    and imaginary parts; each part is decoded as ``v - 65536 * (v >= 32768)``.

    Parameters
    ----------
    name : str
        A key of ``OPENRADAR_CAPTURES``: ``"simple_frame_1"`` (128 x 128) or
        ``"doppler_example"`` (128 x 256).
    directory : str or Path, optional
        The captures root holding ``openradar/``; default :func:`default_data_dir`.

    Returns
    -------
    numpy.ndarray
        complex128, shape (chirps, samples), integer-valued parts in -32768..32767.

    Raises
    ------
    RadarConfigError
        Unknown ``name``; the folder or file is missing, unreadable, of the wrong dtype or
        shape, or holds values that are not 16-bit codes.

    Examples
    --------
    A stand-in file whose codes decode to ``-1 + 1j`` (65535 is -1, 1 stays 1):

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     (Path(tmp) / "openradar").mkdir()
    ...     raw = np.full((128, 128), 65535.0) + 1j
    ...     np.save(Path(tmp) / "openradar" / "simple_frame_1.npy", raw)
    ...     frame = load_openradar("simple_frame_1", tmp)
    >>> frame.shape, frame.dtype, complex(frame[0, 0])
    ((128, 128), dtype('complex128'), (-1+1j))
    """
    shape = OPENRADAR_CAPTURES.get(name)
    if shape is None:
        raise RadarConfigError(f"unknown OpenRadar capture {name!r}; captures: "
                               f"{', '.join(sorted(OPENRADAR_CAPTURES))}")
    path = _folder(directory, "openradar") / f"{name}.npy"
    raw = _load(path, "complex", shape)
    parts = np.stack([raw.real, raw.imag])
    bad = (parts < 0) | (parts >= _UINT16_SPAN) | (parts != np.floor(parts))
    if np.any(bad):
        first = parts[bad][0]
        raise RadarConfigError(
            f"capture file {path} holds {int(np.count_nonzero(bad))} values that are not "
            f"unsigned 16-bit codes 0..65535 (first: {first!r}); expected raw ADC codes"
        )
    signed = parts - _UINT16_SPAN * (parts >= _UINT16_SPAN // 2)
    return (signed[0] + 1j * signed[1]).astype(np.complex128)
