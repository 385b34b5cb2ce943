"""Small files that declare or inflate to gigabytes: deflate bombs for every reader.

Each is built in milliseconds: a deflate stream of zeros is one 1 MiB block compressed
after a full flush (1 037 bytes), repeated — so a 3.9 GiB bomb is 4 MB.  Their checksums
(zlib's Adler-32, the zip CRC) are not those of the data: a reader must refuse them
long before it could check one.

Examples
--------
>>> len(deflate_zeros(64 << 20)) < 80_000
True
>>> import zlib
>>> len(zlib.decompressobj(-15).decompress(deflate_zeros(4 << 20, raw=True), 1 << 30))
4194304
"""

from __future__ import annotations

import io
import struct
import zlib
from pathlib import Path

import numpy as np

_MIB = 1 << 20


def deflate_zeros(n_bytes: int, *, raw: bool = False, prefix: bytes = b"") -> bytes:
    """A deflate stream of ``prefix`` then ``n_bytes`` zeros (rounded up to MiB); zlib-wrapped
    unless ``raw`` (zip members), not terminated with a valid checksum."""
    c = zlib.compressobj(9, zlib.DEFLATED, -15 if raw else 15)
    head = c.compress(prefix) + c.flush(zlib.Z_FULL_FLUSH)
    block = c.compress(bytes(_MIB)) + c.flush(zlib.Z_FULL_FLUSH)
    return head + block * -(-n_bytes // _MIB) + c.flush()


def npy_header(shape: tuple, descr: str = "<f8") -> bytes:
    """The magic and 1.0 header of a ``.npy`` declaring ``shape`` of ``descr``."""
    text = repr({"descr": descr, "fortran_order": False, "shape": tuple(shape)}).encode()
    text += b" " * (63 - (len(text) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text


def zip_deflated(name: str, stream: bytes, file_size: int) -> bytes:
    """A zip holding one deflated member ``name`` of raw deflate ``stream`` that declares
    ``file_size`` uncompressed bytes (< 4 GiB: no zip64), CRC 0."""
    encoded = name.encode()
    local = struct.pack("<4sHHHHHIIIHH", b"PK\x03\x04", 20, 0, 8, 0, 0x21, 0, len(stream),
                        file_size, len(encoded), 0) + encoded
    central = struct.pack("<4sHHHHHHIIIHHHHHII", b"PK\x01\x02", 20, 20, 0, 8, 0, 0x21, 0,
                          len(stream), file_size, len(encoded), 0, 0, 0, 0, 0, 0) + encoded
    start = len(local) + len(stream)
    end = struct.pack("<4sHHHHIIH", b"PK\x05\x06", 0, 0, 1, 1, len(central), start, 0)
    return local + stream + central + end


def npz_bomb(shape: tuple, descr: str = "<f8") -> bytes:
    """An ``.npz`` whose one deflated member ``x.npy`` declares ``shape`` and inflates to it."""
    head = npy_header(shape, descr)
    need = int(np.prod(shape, dtype=object)) * np.dtype(descr).itemsize
    return zip_deflated("x.npy", deflate_zeros(need, raw=True, prefix=head), len(head) + need)


def _mat_header() -> bytes:
    text = b"MATLAB 5.0 MAT-file, written by a test"
    return text.ljust(116, b" ") + bytes(8) + struct.pack("<H", 0x0100) + b"IM"


def _sub(mdtype: int, data: bytes) -> bytes:
    return struct.pack("<II", mdtype, len(data)) + data + bytes(-len(data) % 8)


def mat_bomb(data_bytes: int, *, dims_bytes: int = 0) -> bytes:
    """A v5 ``.mat`` of one compressed variable ``x`` listed as a 1 x 1 double whose data
    element declares and inflates to ``data_bytes``; or, with ``dims_bytes``, whose
    dimensions element does (what listing the variables reads)."""
    flags = _sub(6, struct.pack("<II", 6, 0))  # miUINT32: mxDOUBLE_CLASS
    if dims_bytes:
        body = flags + struct.pack("<II", 5, dims_bytes)  # miINT32 dimensions, then zeros
        fill = dims_bytes
    else:
        body = (flags + _sub(5, struct.pack("<ii", 1, 1)) + _sub(1, b"x")
                + struct.pack("<II", 9, data_bytes))  # miDOUBLE of data_bytes, then zeros
        fill = data_bytes
    prefix = struct.pack("<II", 14, len(body) + fill) + body  # miMATRIX
    stream = deflate_zeros(fill, prefix=prefix)
    return _mat_header() + struct.pack("<II", 15, len(stream)) + stream


def mat_file(arrays: dict) -> bytes:
    """A compressed v5 ``.mat`` of ``arrays`` (scipy's writer), as bytes."""
    from scipy.io import savemat

    out = io.BytesIO()
    savemat(out, arrays, do_compression=True)
    return out.getvalue()


def mat_uncompressed_bomb(nbytes: int) -> bytes:
    """A v5 ``.mat`` whose one uncompressed variable (a 1 x 1 double) declares ``nbytes``
    in its tag and a data element of as many: a reader that trusts either reserves them."""
    body = (_sub(6, struct.pack("<II", 6, 0)) + _sub(5, struct.pack("<ii", 1, 1))
            + _sub(1, b"x") + struct.pack("<II", 9, nbytes) + bytes(8))
    return _mat_header() + struct.pack("<II", 14, nbytes) + body


def mat_v4_bomb(rows: int, cols: int) -> bytes:
    """A v4 ``.mat`` header declaring a ``rows`` x ``cols`` double ``x`` and 8 bytes of data."""
    return struct.pack("<iiiii", 0, rows, cols, 0, 2) + b"x\0" + bytes(8)


_GIB = 1 << 30


def reader_bombs(tmp: Path) -> dict[str, tuple[str, str]]:
    """One small bomb per reader: name -> (the call reading it, what its refusal must say).

    The files (4 MB at most, declaring or inflating to 2-4 GiB) are written into ``tmp``;
    each call is Python source to run in a fresh (capped) interpreter.
    """
    files = {
        "in.npz": npz_bomb((int(3.9 * _GIB) // 8,)),
        "lying.npz": zip_deflated("x.npy", deflate_zeros(3 * _GIB, raw=True, prefix=npy_header(
            (2,))), len(npy_header((2,))) + 16),  # the zip entry says 16 bytes of data
        "framed.npz": zip_deflated("x.npy", deflate_zeros(_GIB, raw=True, prefix=npy_header(
            (int(4.1 * _GIB) // 32, 4))), 1 << 20),  # frames of the port, over 4 GiB
        "data.mat": mat_bomb(int(3.9 * _GIB)),
        "dims.mat": mat_bomb(0, dims_bytes=3 * _GIB),
        "tag.mat": mat_uncompressed_bomb(4 * _GIB - 64),
        "v4.mat": mat_v4_bomb(16_000, 16_000),
        "in.npy": npy_header((10**12,)) + bytes(16),
        "art.npz": npz_bomb((int(3.9 * _GIB) // 8,)),
    }
    for name, data in files.items():
        (tmp / name).write_bytes(data)
    with (tmp / "big.bin").open("wb") as f:
        f.truncate(512 << 20)
    (tmp / "frames").mkdir()
    for i in range(2):
        np.save(tmp / "frames" / f"f{i}.npy", np.zeros(4))
    (tmp / "frames" / "f2.npy").write_bytes(npy_header((10**12,)) + bytes(16))
    arrays = ("from radarsnn.cli.arrays import load_arrays; "
              "load_arrays([{p!r}], ['x'], 'chain c', shapes={{'x': {port}}})")
    return {
        "npz input": (arrays.format(p=str(tmp / "in.npz"), port=(4,)),
                      "but the port takes (4,)"),
        "npz member inflating past its size": (
            arrays.format(p=str(tmp / "lying.npz"), port=(4,)), "not a readable .npz archive"),
        "npz framed input over 4 GiB": (arrays.format(p=str(tmp / "framed.npz"), port=(4,)),
                                        "over the limit of 4294967296"),
        "mat data element": (arrays.format(p=str(tmp / "data.mat"), port=(1,)),
                             "inflates to more than"),
        "mat dimensions": (arrays.format(p=str(tmp / "dims.mat"), port=(1,)),
                           "not a readable .mat"),
        "mat uncompressed tag": (arrays.format(p=str(tmp / "tag.mat"), port=(1,)),
                                 "holds a data element of 4294967232 bytes"),
        "mat v4 header": (arrays.format(p=str(tmp / "v4.mat"), port=(16_000, 16_000)),
                          "but the file holds 30"),
        "npy input": (arrays.format(p=str(tmp / "in.npy"), port=(4,)), "over the limit"),
        "bin capture": ("from radarsnn.cli.arrays import load_arrays; load_arrays("
                        f"[{str(tmp / 'big.bin')!r}], ['x'], 'c', bin_layout='samples=256,"
                        "chirps=128,rx=4', shapes={'x': (4, 64, 256)})", "but the port takes"),
        "artifact arrays.npz": ("from pathlib import Path; from backends.npz_reader import "
                                f"read_npz; read_npz(Path({str(tmp / 'art.npz')!r})."
                                "read_bytes(), Path('arrays.npz'))", "is compressed"),
        "classifier weights": ("from ir.classifier_forward.weights import load_weights; "
                               "from ir.ops.classify import Classifier; load_weights(Classifier."
                               f"model_construct(weights={str(tmp / 'in.npz')!r}), (16, 16), "
                               "'cls')", "over the limit"),
        "folder frame": ("from radarsnn.sweep.frames import load_frames; from radarsnn.sweep."
                         "sections import FolderFrames; load_frames(FolderFrames(source='folder', "
                         f"path='frames'), {str(tmp)!r}, 0, 1, calibration=True)",
                         "over the limit"),
    }
