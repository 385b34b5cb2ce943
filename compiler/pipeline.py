"""The compile pipeline: the passes ``compile_graph`` runs, built from the compile options.

The one place where the compile options become the passes' typed fields (a pass never
reads the options mapping): :func:`default_pipeline` lists the passes in order,
:func:`calibrate_pass` and :func:`lower_pass` fill the two passes with options, and
:func:`motif_settings` fills every motif's typed option model.  :data:`EXTRA_OPTIONS`
lists the options ``compile_graph`` accepts in ``options=``.

Examples
--------
>>> [p.name for p in default_pipeline({}, hardware=True)][-4:]
['quantize', 'split', 'place', 'report']
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ValidationError

from compiler.compile_guards import limits_from_options
from compiler.lowering.options import MOTIF_OPTION_MODELS
from compiler.passes import Pass, Verify
from compiler.passes.calibrate import Calibrate
from compiler.passes.fuse_linear import FuseLinear
from compiler.passes.lower import Lower
from compiler.passes.place import Place
from compiler.passes.quantize import Quantize
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.passes.static_split import StaticSplit, StaticSplitOptions
from ir.errors import CompileError
from ir.model import short_repr

__all__ = ["EXTRA_OPTIONS", "calibrate_pass", "default_pipeline", "lower_pass",
           "motif_settings"]


#: Options ``compile_graph`` accepts in ``options=`` besides its named arguments.
EXTRA_OPTIONS = {
    "headroom": "calibration headroom factor >= 1 (static policy)",
    "input_bounds": "{input node id: max |value|} when no calibration inputs are given",
    "long_delays": "quantize: 'relay' (default) or 'error' for delays beyond the target's maximum",
    "repetitions": "split/place: 'auto' | 'spatial' | 'temporal' (time-multiplex repeated stages)",
    "frame_rate_hz": "report: frames per second (default from the chain or 10)",
    "real_bits": "report: bits per real sample of frame I/O (default 16)",
    "n_angle_bins": "report: angle bins of an RA map the chain does not compute (CARRADA: 256; "
                    "default none: an ra_map row only when the chain computes one)",
    "max_memory_bytes": "refuse chains whose estimated compile memory exceeds this, bytes",
    "max_time_s": "refuse chains whose estimated compile time exceeds this, s",
    # typed fields of their pass or motif (the description says what the value must be);
    # time_steps, weight_bits and calibration are compile_graph's named arguments
    **{n: f"{f.description} — {(m.__doc__ or '').splitlines()[0]}"
       for m in (StaticSplitOptions, *MOTIF_OPTION_MODELS) for n, f in m.model_fields.items()
       if n not in ("time_steps", "weight_bits", "calibration", "headroom")},
}


def motif_settings(options: Mapping[str, Any]) -> dict[type[BaseModel], BaseModel]:
    """Every model of :data:`~compiler.lowering.options.MOTIF_OPTION_MODELS` filled from
    ``options`` (None: the default).

    Examples
    --------
    >>> from compiler.lowering.options import CfarOptions, RateOptions
    >>> settings = motif_settings({"time_steps": 64, "cfar_ties": "exact"})
    >>> settings[CfarOptions].time_steps, settings[CfarOptions].cfar_ties
    (64, 'exact')
    >>> motif_settings({})[RateOptions].time_steps, motif_settings({})[CfarOptions].time_steps
    (2000, 100)
    >>> motif_settings({"cfar_ties": "often"})
    Traceback (most recent call last):
    ...
    ir.errors.CompileError: compile option cfar_ties='often' must be balanced or exact

    Raises
    ------
    CompileError
        A value its field refuses, naming the option, the value and the rule.
    """
    out: dict[type[BaseModel], BaseModel] = {}
    for model in MOTIF_OPTION_MODELS:
        given = {k: options[k] for k in model.model_fields if options.get(k) is not None}
        try:
            out[model] = model.model_validate(given)
        except ValidationError as err:
            name = str(err.errors()[0]["loc"][0])
            what = model.model_fields[name].description or name
            raise CompileError(f"compile option {name}={short_repr(given[name])} must be "
                               f"{what}") from None
    return out


def calibrate_pass(options: Mapping[str, Any]) -> Calibrate:
    """The ``calibrate`` pass with its fields from compile options (absent: the defaults).

    Examples
    --------
    >>> calibrate_pass({"calibration": "per-input", "headroom": 1.5}).policy
    'per-input'
    """
    opts = {k: v for k, v in options.items() if v is not None}
    return Calibrate(policy=str(opts.get("calibration", "static")),
                     headroom=float(opts.get("headroom", 1.0)),
                     input_bounds=tuple((str(k), float(v))
                                        for k, v in dict(opts.get("input_bounds", {})).items()),
                     max_memory_bytes=limits_from_options(opts)[0])


def lower_pass(options: Mapping[str, Any]) -> Lower:
    """The ``lower`` pass with the user's motifs and every motif's typed options.

    Raises
    ------
    CompileError
        A motif option its field refuses (:func:`motif_settings`).

    Examples
    --------
    >>> from compiler.lowering.options import CfarOptions
    >>> p = lower_pass({"motifs": {"dft": "rate"}, "time_steps": 64})
    >>> p.motifs, next(s for s in p.settings if isinstance(s, CfarOptions)).time_steps
    ((('dft', 'rate'),), 64)
    """
    opts = {k: v for k, v in options.items() if v is not None}
    return Lower(motifs=tuple(sorted(dict(opts.get("motifs", {})).items())),
                 settings=tuple(motif_settings(opts).values()))


def default_pipeline(options: Mapping[str, Any], *, hardware: bool = False) -> list[Pass]:
    """The passes ``compile_graph`` runs, in order (the allocation passes need a target).

    The one place where the compile options become the passes' typed fields (a pass
    never reads the options mapping); the motifs' own options reach them through
    :class:`~compiler.lowering.LoweringContext`.

    Parameters
    ----------
    options : mapping
        Checked compile options (:func:`compiler.option_checks.check_options`); absent
        ones take the pass's default.
    hardware : bool
        Add the allocation passes (quantize, split, place, report).

    Raises
    ------
    CompileError
        A pass refuses its option's value (e.g. an unknown calibration policy).

    Examples
    --------
    >>> [p.name for p in default_pipeline({"calibration": "per-input"})]
    ['verify', 'fuse-linear', 'static-split', 'calibrate', 'lower']
    >>> default_pipeline({"headroom": 2})[3].headroom
    2.0
    """
    opts = {k: v for k, v in options.items() if v is not None}
    split = StaticSplitOptions.model_validate(
        {k: opts[k] for k in StaticSplitOptions.model_fields if k in opts})
    passes: list[Pass] = [
        Verify(), FuseLinear(),
        StaticSplit(mode=split.static_split,
                    motifs=tuple(sorted(dict(opts.get("motifs", {})).items()))),
        calibrate_pass(opts), lower_pass(opts)]
    if hardware:
        mode = str(opts.get("repetitions", "auto"))
        passes += [Quantize(long_delays=opts.get("long_delays", "relay")),
                   Split(repetitions=mode), Place(repetitions=mode),
                   ReportPass(frame_rate_hz=opts.get("frame_rate_hz"),
                              real_bits=int(opts.get("real_bits", 16)),
                              n_angle_bins=opts.get("n_angle_bins"))]
    return passes
