"""``.npy`` arrays named on the command line (``radarsnn run -i``, ``--calibration``): read
without unpickling, the header checked before numpy allocates anything.
"""

from __future__ import annotations

from ir.errors import RadarSNNError

__all__ = ["MAX_NPY_BYTES", "load_arrays", "read_npy"]

#: Largest array a ``.npy`` input may declare: 4 GiB (the artifacts' array limit; a bigger
#: input could not be simulated within the default memory limit anyway).
MAX_NPY_BYTES = 4 << 30


def load_arrays(items: list[str], ports: list[str], what: str) -> dict:
    """``[PORT=]FILE.npy`` arguments → arrays by port (a bare file needs exactly one port).

    Raises
    ------
    RadarSNNError
        An unknown port, a bare file with several ports, or a file that is not
        a readable ``.npy`` array (pickled object arrays are refused).
    """

    arrays = {}
    for item in items:
        port, sep, path = item.rpartition("=")
        if not sep:
            if len(ports) != 1:
                raise RadarSNNError(f"{what} has input ports {ports}; name one as PORT=FILE.npy "
                                    f"(got {item!r})")
            port, path = ports[0], item
        if port not in ports:
            raise RadarSNNError(f"{what} has no input port {port!r}; its ports are {ports}")
        arrays[port] = read_npy(path, f"input {path!r} for port {port!r}")
    return arrays


def read_npy(path: str, what: str):
    """One array from a ``.npy`` file, never unpickling; ``what`` names it in errors.

    The header is read first: object dtypes are refused, the data it declares must be
    at most :data:`MAX_NPY_BYTES` and in the file, so a damaged or forged header cannot
    make numpy allocate or parse beyond the file (a sparse file declaring 10¹² values
    included).

    Raises
    ------
    RadarSNNError
        Missing, empty, truncated or damaged files, not a regular file, object arrays,
        a declared size over :data:`MAX_NPY_BYTES`, ``.npz`` archives.
    """
    import os
    import stat
    import tokenize

    import numpy as np

    fmt = np.lib.format
    failures = (OSError, ValueError, EOFError, SyntaxError, tokenize.TokenError, OverflowError,
                MemoryError, TypeError)
    try:
        with open(path, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):  # /dev/zero, a FIFO, a tty
                raise RadarSNNError(f"cannot read {what}: not a regular file")
            if f.read(4) == b"PK\x03\x04":
                raise RadarSNNError(f"cannot read {what}: it is a .npz archive; give one array "
                                    "per .npy file (np.save)")
            f.seek(0)
            version = fmt.read_magic(f)
            shape, _, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                               else fmt.read_array_header_2_0(f))
            if dtype.hasobject:
                raise RadarSNNError(f"cannot read {what}: object arrays are refused (loading "
                                    "them would unpickle code); save a numeric array")
            need = int(np.prod(shape, dtype=object)) * dtype.itemsize
            have = _remaining(f)
            if need > MAX_NPY_BYTES:
                raise RadarSNNError(f"cannot read {what}: the header declares {shape} {dtype} "
                                    f"({need} bytes), over the limit of {MAX_NPY_BYTES} bytes "
                                    "(MAX_NPY_BYTES); give fewer frames per file")
            if have < need:
                raise RadarSNNError(f"cannot read {what}: the header declares {shape} {dtype} "
                                    f"({need} bytes) but the file holds {have}; truncated?")
        return np.load(path, allow_pickle=False)
    except failures as err:
        raise RadarSNNError(f"cannot read {what}: {err or type(err).__name__}") from None


def _remaining(f) -> int:
    here = f.tell()
    end = f.seek(0, 2)
    f.seek(here)
    return end - here
