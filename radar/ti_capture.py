"""TI mmWave raw ADC captures (``.bin`` files written by mmWave Studio / the DCA1000EVM).

A capture is a headerless stream of little-endian signed 16-bit words (the DCA1000 records
two's complement), frame after frame. In a frame, the chirps come loop by loop and, in a
loop, TX slot by TX slot (TDM-MIMO). The word order inside a chirp depends on the device's
LVDS interface, as TI documents it in application report SWRA581B, "Mmwave Radar Device ADC
Raw Data Capture", §5 (xWR12xx/xWR14xx) and §6 (xWR16xx/xWR18xx/IWR6843), and its
``readDCA1000.m``:

* ``xwr16xx`` (2 LVDS lanes; also xWR18xx, IWR6843): RX by RX, each RX's samples in time
  order. Complex data is stored in groups of four words ``I0 I1 Q0 Q1``: two samples' I
  parts, then their Q parts. Real data is the plain sample sequence.
* ``xwr14xx`` (4 LVDS lanes, one RX per lane; also xWR12xx): sample by sample, the 4 lanes
  interleaved. Complex: ``I(rx0) I(rx1) I(rx2) I(rx3) Q(rx0) … Q(rx3)`` per sample time;
  real: ``rx0 rx1 rx2 rx3``. The stream always has 4 lanes; unused lanes hold zeros.

:func:`read_ti_bin` returns the project's cube order :data:`TI_AXES`
``[frame, rx, chirp, sample]``. The rx axis holds the virtual channels ``tx * n_rx + rx``,
like :func:`radar.scene.simulate_frame`, and the chirp axis holds the loops, i.e. chirps
per TX, like :attr:`radar.config.RadarConfig.n_chirps`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ir.errors import RadarConfigError
from radar._checks import _positive_int
from radar.files import check_frame_shape, open_regular

__all__ = ["LAYOUT_KEYS", "MAX_CAPTURE_BYTES", "TI_AXES", "TI_DEVICES", "TiBinLayout",
           "read_ti_bin"]

#: Axis names of :func:`read_ti_bin`'s result, the order of the chains' ``adc_input`` cubes.
TI_AXES = ("frame", "rx", "chirp", "sample")

#: Device family spelled on the command line -> the LVDS word order it uses.
TI_DEVICES = {"xwr16xx": "xwr16xx", "xwr18xx": "xwr16xx", "iwr6843": "xwr16xx",
              "xwr14xx": "xwr14xx", "xwr12xx": "xwr14xx"}

#: Most bytes the decoded array may take (4 GiB, like the CLI's ``.npy`` inputs).
MAX_CAPTURE_BYTES = 4 << 30

_LANES_XWR14XX = 4
#: Words decoded at a time (their temporaries, ~40 bytes a word, come on top of the result).
_PIECE_WORDS = 1 << 20


#: ``--bin-layout`` key -> the :class:`TiBinLayout` field it sets (either name is accepted).
LAYOUT_KEYS = {"samples": "n_samples", "chirps": "n_chirps", "rx": "n_rx", "tx": "n_tx",
               "bits": "adc_bits"}


@dataclass(frozen=True)
class TiBinLayout:
    """How one frame of a TI raw ADC capture is laid out.

    Parameters
    ----------
    n_samples : int
        ADC samples per chirp (``profileCfg`` numAdcSamples).
    n_chirps : int
        Chirps per TX per frame: the chirp loops (``frameCfg`` loops).
    n_rx : int
        Enabled receive channels (``channelCfg``); 4 for ``xwr14xx``, whose stream has 4 lanes.
    n_tx : int
        TX slots per loop (TDM-MIMO); a frame holds ``n_chirps * n_tx`` chirps.
    complex : bool
        IQ (complex) samples; False for real-only ADC output (``adcCfg``).
    device : str
        A key of :data:`TI_DEVICES`: ``"xwr16xx"`` (default; also xwr18xx, iwr6843) or
        ``"xwr14xx"`` (also xwr12xx).
    adc_bits : int
        ADC bits per sample, 12, 14 or 16; codes of 12- and 14-bit captures are
        sign-extended as ``readDCA1000.m`` does.

    Raises
    ------
    RadarConfigError
        A count that is not a positive integer, an unknown device, ``n_rx != 4`` for
        ``xwr14xx``, an odd number of complex samples per frame for ``xwr16xx`` (its
        ``I0 I1 Q0 Q1`` pairs would cross frames), or ``adc_bits`` not 12, 14 or 16.

    Examples
    --------
    >>> layout = TiBinLayout(n_samples=256, n_chirps=128, n_rx=4)
    >>> layout.frame_bytes, layout.shape(frames=2)
    (524288, (2, 4, 128, 256))
    """

    n_samples: int
    n_chirps: int
    n_rx: int
    n_tx: int = 1
    complex: bool = True
    device: str = "xwr16xx"
    adc_bits: int = 16

    def __post_init__(self) -> None:
        for name in ("n_samples", "n_chirps", "n_rx", "n_tx"):
            object.__setattr__(self, name, _positive_int(getattr(self, name), name))
        family = TI_DEVICES.get(str(self.device).lower())
        if family is None:
            raise RadarConfigError(f"device={self.device!r} is not a TI device family radarsnn "
                                   f"reads; use one of {', '.join(TI_DEVICES)}")
        object.__setattr__(self, "device", family)
        if family == "xwr14xx" and self.n_rx != _LANES_XWR14XX:
            raise RadarConfigError(
                f"n_rx={self.n_rx}: an xwr14xx capture always carries 4 LVDS lanes, unused "
                "ones zero (SWRA581B §5); read it with n_rx=4 and keep the enabled channels, "
                "e.g. adc[:, :2]")
        values = self.n_samples * self.n_rx * self.n_chirps * self.n_tx
        if family == "xwr16xx" and self.complex and values % 2:
            raise RadarConfigError(
                f"samples={self.n_samples}, rx={self.n_rx}, chirps={self.n_chirps}, "
                f"tx={self.n_tx}: an xwr16xx complex capture stores samples in pairs "
                f"(I0 I1 Q0 Q1, SWRA581B §6), so a frame of {values} complex samples (odd) "
                "would split a pair across frames; check the counts against the sensor "
                "configuration (profileCfg, frameCfg, channelCfg)")
        if self.adc_bits not in (12, 14, 16):
            raise RadarConfigError(f"adc_bits={self.adc_bits!r}: TI captures hold 12-, 14- or "
                                   "16-bit codes; use 12, 14 or 16")

    @classmethod
    def from_config(cls, config, *, device: str = "xwr16xx") -> TiBinLayout:
        """The layout of a capture made with :class:`radar.config.RadarConfig` ``config``.

        Examples
        --------
        >>> from radar.config import preset
        >>> TiBinLayout.from_config(preset("carrada")).shape(frames=1)
        (1, 8, 64, 256)
        """
        return cls(n_samples=config.n_samples, n_chirps=config.n_chirps, n_rx=config.n_rx,
                   n_tx=config.n_tx, complex=config.iq, device=device,
                   adc_bits=min(16, max(12, config.adc_bits)))

    @classmethod
    def parse(cls, text: str) -> TiBinLayout:
        """A layout from its command-line spelling (``--bin-layout``).

        ``samples=N,chirps=M,rx=R`` are required; ``tx=T`` (default 1), ``complex`` or
        ``real`` (default complex), ``device=D`` (default xwr16xx) and ``bits=B``
        (default 16) are optional. ``chirps`` counts chirps per TX (the loops). Each key
        may also be spelled as the field it sets (:data:`LAYOUT_KEYS`): ``n_samples``,
        ``n_chirps``, ``n_rx``, ``n_tx``, ``adc_bits``, ``complex=true|false`` — the names
        of ``TiBinLayout(...)``.

        Raises
        ------
        RadarConfigError
            An item that is not ``KEY=VALUE`` or a flag, an unknown key, a value that is not
            a positive integer in ASCII digits, a missing required key; or what
            :class:`TiBinLayout` refuses.

        Examples
        --------
        >>> TiBinLayout.parse("samples=256,chirps=64,rx=4,tx=2,complex").shape(frames=1)
        (1, 8, 64, 256)
        >>> cli = TiBinLayout.parse("n_samples=256,n_chirps=64,n_rx=4,n_tx=2,complex=false")
        >>> cli == TiBinLayout(n_samples=256, n_chirps=64, n_rx=4, n_tx=2, complex=False)
        True
        >>> TiBinLayout.parse("samples=256,rx=4")
        Traceback (most recent call last):
        ...
        ir.errors.RadarConfigError: --bin-layout 'samples=256,rx=4' lacks chirps=; \
give samples=N,chirps=M,rx=R[,tx=T][,complex|real][,device=D][,bits=B]
        """
        usage = "samples=N,chirps=M,rx=R[,tx=T][,complex|real][,device=D][,bits=B]"
        keys = {**LAYOUT_KEYS, **{f: f for f in LAYOUT_KEYS.values()}}
        fields: dict[str, object] = {}
        for item in (part.strip() for part in str(text).split(",")):
            key, sep, value = item.partition("=")
            if not sep and item in ("complex", "real"):
                fields["complex"] = item == "complex"
            elif sep and key == "complex" and value.lower() in ("true", "false"):
                fields["complex"] = value.lower() == "true"
            elif sep and key == "device":
                fields["device"] = value
            elif sep and key in keys:
                if not (value.isascii() and value.isdigit()) or len(value) > 9:  # not '²'
                    raise RadarConfigError(f"--bin-layout {text!r}: {key}={value!r} is not a "
                                           "positive integer (ASCII digits 0-9, at most 9)")
                fields[keys[key]] = int(value)
            else:
                raise RadarConfigError(f"--bin-layout {text!r}: {item!r} is not one of the "
                                       f"items of {usage}")
        for key in ("samples", "chirps", "rx"):
            if LAYOUT_KEYS[key] not in fields:
                raise RadarConfigError(f"--bin-layout {text!r} lacks {key}=; give {usage}")
        return cls(**fields)

    @property
    def words_per_frame(self) -> int:
        """16-bit words in one frame."""
        return (self.n_samples * self.n_rx * self.n_chirps * self.n_tx
                * (2 if self.complex else 1))

    @property
    def frame_bytes(self) -> int:
        """Bytes in one frame."""
        return 2 * self.words_per_frame

    def shape(self, frames: int) -> tuple[int, int, int, int]:
        """The decoded shape ``[frame, rx, chirp, sample]`` (rx = ``n_tx * n_rx`` virtual)."""
        return (frames, self.n_tx * self.n_rx, self.n_chirps, self.n_samples)

    def describe(self) -> str:
        """The layout as the command line spells it (``--bin-layout``)."""
        return (f"samples={self.n_samples},chirps={self.n_chirps},rx={self.n_rx},"
                f"tx={self.n_tx},{'complex' if self.complex else 'real'},"
                f"device={self.device},bits={self.adc_bits}")


def read_ti_bin(path: str | Path, layout: TiBinLayout, *, first_frame: int = 0,
                n_frames: int | None = None, max_bytes: int = MAX_CAPTURE_BYTES,
                frame_shape: tuple[int, ...] | None = None, squeeze: bool = False) -> np.ndarray:
    """Read a TI raw ADC capture into ``[frame, rx, chirp, sample]`` ADC codes.

    The result is always 4-D — one frame too, as ``(1, rx, chirp, sample)`` — unless
    ``squeeze=True``, which drops the frame axis of a one-frame result (the
    ``[rx, chirp, sample]`` cube a chain's ``adc_input`` takes; ``radarsnn run`` reads a
    one-frame ``.bin`` that way).

    Parameters
    ----------
    path : str or Path
        The ``.bin`` file (one file of a capture; mmWave Studio splits long ones at 1 GiB).
    layout : TiBinLayout
        Samples, chirps, RX, TX, complex or real, device family, ADC bits.
    first_frame : int
        The first frame to read (default 0).
    n_frames : int, optional
        How many frames to read (default: all from ``first_frame``).
    max_bytes : int
        Most bytes the decoded array may take.
    frame_shape : tuple of int, optional
        One frame of the port the capture is for: ``layout.shape(1)[1:]`` must be it,
        checked before anything is read.
    squeeze : bool
        Drop the frame axis when the result holds one frame (default False: always 4-D).

    Returns
    -------
    numpy.ndarray
        complex128 (IQ) or float64 (real), shape ``layout.shape(frames)``, axes
        :data:`TI_AXES` (with ``squeeze`` and one frame: ``TI_AXES[1:]``); virtual channel
        ``tx * n_rx + rx``.

    Raises
    ------
    RadarConfigError
        The file is missing, unreadable or empty, its size is not a whole number of frames
        of ``layout``, the frames asked for are not in it, or the result would exceed
        ``max_bytes``, or the layout's frame is not ``frame_shape``. Each message names
        the file, its size and the frame size.

    Notes
    -----
    The result is allocated once and filled a piece at a time (about 2²⁰ words, or one
    frame's or a few loops' worth), so decoding needs the result plus a few tens of MB,
    not three times the result.

    Examples
    --------
    One frame, 1 RX, 4 complex samples, 1 chirp: words ``I0 I1 Q0 Q1 I2 I3 Q2 Q3``.

    >>> import tempfile
    >>> words = np.array([1, 2, 10, 20, 3, 4, 30, 40], dtype="<i2")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     words.tofile(Path(tmp) / "adc.bin")
    ...     adc = read_ti_bin(Path(tmp) / "adc.bin", TiBinLayout(4, 1, 1))
    >>> adc.shape, adc[0, 0, 0].tolist()
    ((1, 1, 1, 4), [(1+10j), (2+20j), (3+30j), (4+40j)])
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     words.tofile(Path(tmp) / "adc.bin")
    ...     read_ti_bin(Path(tmp) / "adc.bin", TiBinLayout(4, 1, 1), squeeze=True).shape
    (1, 1, 4)
    """
    path = Path(path)
    frame_bytes = layout.frame_bytes
    try:
        size_bytes = os.stat(path).st_size
    except OSError as err:
        raise RadarConfigError(f"TI capture {path}: cannot read it "
                               f"({err.strerror or err})") from None
    if not path.is_file() or size_bytes == 0:
        what = "empty" if path.is_file() else "not a regular file"
        raise RadarConfigError(f"TI capture {path} is {what}; expected frames of {frame_bytes} "
                               f"bytes ({layout.describe()})")
    total, extra = divmod(size_bytes, frame_bytes)
    if extra:
        raise RadarConfigError(
            f"TI capture {path} holds {size_bytes} bytes, not a multiple of one frame's "
            f"{frame_bytes} bytes ({layout.describe()}; {size_bytes / frame_bytes:.4g} frames, "
            f"{extra} bytes left over); check samples, chirps (loops per TX), rx, tx and "
            "complex/real against the sensor configuration (profileCfg, frameCfg, channelCfg, "
            "adcCfg), or cut the file to whole frames")
    if isinstance(first_frame, bool) or not isinstance(first_frame, int | np.integer):
        raise RadarConfigError(f"first_frame={first_frame!r} must be a non-negative integer")
    first = int(first_frame)
    count = total - first if n_frames is None else _positive_int(n_frames, "n_frames")
    if first < 0 or count < 1 or first + count > total:
        raise RadarConfigError(f"TI capture {path} holds {total} frame(s) of {frame_bytes} bytes "
                               f"(0..{total - 1}); {count if count > 0 else 'the'} frame(s) "
                               f"from {first} are not all in it: lower first_frame or n_frames")
    check_frame_shape(f"TI capture {path} ({layout.describe()})", layout.shape(count),
                      frame_shape)
    out_bytes = count * layout.words_per_frame * 8  # float64 per word
    if out_bytes > max_bytes:
        raise RadarConfigError(
            f"TI capture {path}: {count} frame(s) decode to {out_bytes} bytes, over the limit "
            f"of {max_bytes} bytes; read fewer frames at a time (n_frames=, first_frame=)")
    out = np.empty(layout.shape(count), dtype=np.complex128 if layout.complex else np.float64)
    tx, rx, loops, n = layout.n_tx, layout.n_rx, layout.n_chirps, layout.n_samples
    by_stream = out.reshape(count, tx, rx, loops, n)  # a view: [frame, tx, rx, loop, sample]
    per_loop = layout.words_per_frame // loops
    with open_regular(path, f"TI capture {path}") as f:
        for fa, fb, la, lb in _pieces(layout, count):
            words = (fb - fa) * layout.words_per_frame if lb - la == loops else \
                (lb - la) * per_loop
            f.seek(2 * ((first + fa) * layout.words_per_frame + la * per_loop))
            raw = np.fromfile(f, dtype="<i2", count=words)
            if raw.size != words:
                raise RadarConfigError(f"TI capture {path} shrank while it was read; read it "
                                       "again")
            cube = _decode(raw.astype(np.int32), layout, fb - fa, lb - la)
            # [frame, loop, tx, rx, sample] -> [frame, tx, rx, loop, sample] of the result
            by_stream[fa:fb, :, :, la:lb] = cube.transpose(0, 2, 3, 1, 4)
    return out[0] if squeeze and count == 1 else out


def _pieces(layout: TiBinLayout, count: int) -> list[tuple[int, int, int, int]]:
    """``(first frame, stop frame, first loop, stop loop)`` of each piece decoded at once.

    Whole frames while a frame is at most :data:`_PIECE_WORDS`, else a few loops of one
    frame. xWR16xx complex words come in ``I0 I1 Q0 Q1`` groups of two samples: a piece
    starts and ends on a group (pieces of loops only when a loop holds an even number of
    samples, of frames only when a frame does; otherwise the capture in one piece).
    """
    loops, per = layout.n_chirps, layout.words_per_frame
    paired = layout.device == "xwr16xx" and layout.complex
    if paired and per % 4:
        return [(0, count, 0, loops)]
    per_loop = per // loops
    if per <= _PIECE_WORDS or (paired and per_loop % 4):
        step = max(1, _PIECE_WORDS // per)
        return [(a, min(a + step, count), 0, loops) for a in range(0, count, step)]
    step = max(1, _PIECE_WORDS // per_loop)
    return [(f, f + 1, a, min(a + step, loops)) for f in range(count)
            for a in range(0, loops, step)]


def _decode(words: np.ndarray, layout: TiBinLayout, frames: int, loops: int) -> np.ndarray:
    """``frames`` x ``loops`` loops of 16-bit words -> ``[frame, loop, tx, rx, sample]`` codes."""
    if layout.adc_bits < 16:  # sign-extend, as readDCA1000.m does
        top = 1 << (layout.adc_bits - 1)
        words = np.where(words >= top, words - (top << 1), words)
    words = words.astype(np.float64)
    n, rx, tx = layout.n_samples, layout.n_rx, layout.n_tx
    if layout.device == "xwr16xx":
        if layout.complex:
            quads = words.reshape(-1, 4)  # I0 I1 Q0 Q1
            flat = np.empty(2 * len(quads), dtype=np.complex128)
            flat.real[0::2], flat.imag[0::2] = quads[:, 0], quads[:, 2]
            flat.real[1::2], flat.imag[1::2] = quads[:, 1], quads[:, 3]
        else:
            flat = words
        return flat.reshape(frames, loops, tx, rx, n)
    # xwr14xx: per sample time, the 4 lanes (I of each, then Q of each if complex)
    if layout.complex:
        octets = words.reshape(-1, 2 * rx)
        lanes = np.empty((len(octets), rx), dtype=np.complex128)
        lanes.real, lanes.imag = octets[:, :rx], octets[:, rx:]
    else:
        lanes = words.reshape(-1, rx)
    return lanes.reshape(frames, loops, tx, n, rx).transpose(0, 1, 2, 4, 3)
