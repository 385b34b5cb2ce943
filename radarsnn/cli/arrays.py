"""Arrays named on the command line (``radarsnn run -i``, ``--calibration``): read without
unpickling, each file's header checked before numpy allocates anything.

``[PORT=]FILE`` where FILE is ``X.npy``; ``X.npz`` (its only array) or ``X.npz:KEY`` — so
``radarsnn run -o out.npz`` can be read back; ``X.mat`` or ``X.mat:VAR`` (MATLAB v4–v7,
:func:`radar.readers.read_mat_array`); or a raw TI capture ``X.bin`` read with the layout
given by ``--bin-layout`` (:func:`radar.ti_capture.read_ti_bin`; a capture of one frame gives
``[rx, chirp, sample]``, of several ``[frame, rx, chirp, sample]``).

When the ports' shapes are known (``shapes=``), each file's declared shape (its header,
variable listing or ``--bin-layout``) is checked against its port before any data is read
or inflated: a file cannot make a reader allocate more than the port could take.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping, Sequence

from ir.errors import RadarSNNError

__all__ = ["INPUT_FORMS", "MAX_NPY_BYTES", "load_arrays", "read_input", "read_npy"]

#: Largest array a ``.npy`` input may declare: 4 GiB (the artifacts' array limit; a bigger
#: input could not be simulated within the default memory limit anyway).
MAX_NPY_BYTES = 4 << 30

#: The input forms, for help texts and messages.
INPUT_FORMS = "X.npy, X.npz[:KEY], X.mat[:VAR] or a TI X.bin (with --bin-layout)"

_KEYED = re.compile(r"^(?P<path>.+\.(?:npz|mat)):(?P<key>[^:/\\]+)$", re.IGNORECASE)


def load_arrays(items: list[str], ports: list[str], what: str, *,
                bin_layout: str | None = None,
                shapes: Mapping[str, Sequence[int]] | None = None) -> dict:
    """``[PORT=]FILE`` arguments → arrays by port (a bare file needs exactly one port).

    Parameters
    ----------
    items : list of str
        The arguments, FILE as in :func:`read_input`.
    ports : list of str
        The input ports (input node ids) of the chain or artifact.
    what : str
        Names the chain or artifact in messages.
    bin_layout : str, optional
        ``--bin-layout`` for ``.bin`` inputs (:meth:`radar.ti_capture.TiBinLayout.parse`).
    shapes : mapping of str to tuple of int, optional
        One frame's shape per port: a file must declare it or ``(frames, *shape)``,
        checked before its data is read (:func:`radar.files.check_frame_shape`).

    Raises
    ------
    RadarSNNError
        An unknown port, a port given twice, a bare file with several ports, a file that
        cannot be read as its form (pickled object arrays are refused), a ``.bin`` input
        without ``--bin-layout`` or ``--bin-layout`` without one.

    Examples
    --------
    >>> load_arrays(["adc=x.npy", "adc=y.npy"], ["adc"], "chain c")
    Traceback (most recent call last):
    ...
    ir.errors.RadarSNNError: chain c: input port 'adc' is given twice ('adc=x.npy' and \
'adc=y.npy'); give each port once
    """
    given: dict[str, tuple[str, str]] = {}  # port -> (argument, file)
    for item in items:
        port, sep, path = item.partition("=")
        if not sep:
            if len(ports) != 1:
                raise RadarSNNError(f"{what} has input ports {ports}; name one as PORT=FILE "
                                    f"(got {item!r})")
            port, path = ports[0], item
        if port not in ports:
            raise RadarSNNError(f"{what} has no input port {port!r}; its ports are {ports}")
        if port in given:
            raise RadarSNNError(f"{what}: input port {port!r} is given twice "
                                f"({given[port][0]!r} and {item!r}); give each port once")
        given[port] = (item, path)
    if bin_layout is not None and not any(_split(path)[0].lower().endswith(".bin")
                                          for _, path in given.values()):
        raise RadarSNNError(f"--bin-layout {bin_layout!r} is given but no input is a .bin "
                            "capture; drop it, or give the capture as PORT=X.bin")
    if bin_layout is not None:  # its own errors first, before any file is read
        from radar.ti_capture import TiBinLayout

        bin_layout = TiBinLayout.parse(bin_layout)
    shapes = shapes or {}
    return {port: read_input(path, port, bin_layout=bin_layout, frame_shape=shapes.get(port))
            for port, (_, path) in given.items()}


def _split(spec: str) -> tuple[str, str | None]:
    """``X.npz:KEY`` → (``X.npz``, ``KEY``); anything else → (spec, None)."""
    match = _KEYED.match(spec)
    return (match["path"], match["key"]) if match else (spec, None)


def read_input(spec: str, port: str, *, bin_layout=None,
               frame_shape: Sequence[int] | None = None):
    """The array for input ``port`` from ``X.npy``, ``X.npz[:KEY]``, ``X.mat[:VAR]`` or ``X.bin``.

    ``frame_shape`` (one frame of the port, optional) is checked against the shape the
    file declares before its data is read or decoded.

    Raises
    ------
    RadarSNNError
        As :func:`read_npy`, :func:`radar.readers.read_npz_array`,
        :func:`radar.readers.read_mat_array` and :func:`radar.ti_capture.read_ti_bin`
        (their messages, which name the file, prefixed with the port); a ``.bin`` without
        ``bin_layout`` (a :class:`radar.ti_capture.TiBinLayout` or its ``--bin-layout``
        spelling).
    """
    path, key = _split(spec)
    suffix = path.lower().rpartition(".")[2]
    if suffix not in ("npz", "mat", "bin"):
        return read_npy(path, f"input {path!r} for port {port!r}", frame_shape=frame_shape)
    from radar.readers import read_mat_array, read_npz_array
    from radar.ti_capture import TiBinLayout, read_ti_bin

    try:
        if suffix == "npz":
            return read_npz_array(path, key, frame_shape=frame_shape)
        if suffix == "mat":
            return read_mat_array(path, key, frame_shape=frame_shape)
        if bin_layout is None:
            raise RadarSNNError(f"{path} is a raw TI capture: give its layout, e.g. "
                                "--bin-layout samples=256,chirps=128,rx=4[,tx=2][,real]"
                                "[,device=xwr14xx] (docs/cli.md, Inputs)")
        layout = (bin_layout if isinstance(bin_layout, TiBinLayout)
                  else TiBinLayout.parse(bin_layout))
        return read_ti_bin(path, layout, frame_shape=frame_shape, squeeze=True)
    except RadarSNNError as err:
        raise type(err)(f"input for port {port!r}: {err}", node=err.node) from None


def read_npy(path: str, what: str, *, frame_shape: Sequence[int] | None = None):
    """One array from a ``.npy`` file, never unpickling; ``what`` names it in errors.

    :func:`radar.readers.read_npy_array` with the limit :data:`MAX_NPY_BYTES`: the header
    is read first: object dtypes are refused, the data it declares must be at most
    :data:`MAX_NPY_BYTES`, in the file and (with ``frame_shape``) the port's shape, so a
    damaged or forged header cannot make numpy allocate or parse beyond the file (a sparse
    file declaring 10¹² values included); a FIFO is refused at once, not waited on.

    Raises
    ------
    RadarSNNError
        Missing, empty, truncated or damaged files, not a regular file, object arrays,
        a declared size over :data:`MAX_NPY_BYTES`, a shape the port does not take,
        ``.npz`` archives (read those by :func:`read_input` under a ``.npz`` name).
    """
    from radar.readers import read_npy_array

    return read_npy_array(path, max_bytes=MAX_NPY_BYTES, frame_shape=frame_shape, what=what)


def bin_layout_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--bin-layout`` (the layout of TI raw ``.bin`` inputs) to a sub-command's parser."""
    p.add_argument("--bin-layout", metavar="LAYOUT",
                   help="layout of TI raw ADC .bin inputs (DCA1000 captures), e.g. "
                        "samples=256,chirps=128,rx=4,tx=2 — keys: samples (per chirp), chirps "
                        "(per TX: the loops), rx, tx (default 1), complex or real (default "
                        "complex), device (xwr16xx, the default, or xwr14xx), bits (default "
                        "16); each key may be spelled as radar.ti_capture.TiBinLayout's field: "
                        "n_samples, n_chirps, n_rx, n_tx, adc_bits; see docs/cli.md")
