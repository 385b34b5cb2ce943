"""The value rules of ``compile_graph``'s options, checked once before any pass runs.

The passes and motifs read their options where they need them; a value of the
wrong type there would surface as a ``TypeError`` deep in a lowering.  Here each
option has one checker in an explicit registry (:data:`OPTION_CHECKS`), so a bad
value is refused up front with a :class:`~ir.errors.CompileError` that names the
option, the value and what it must be.  ``None`` means "the default": such an
option is dropped.  Options without a checker here are passed through.

Examples
--------
>>> check_options({"headroom": 1.5, "cfar_range": None, "max_time_s": None}, time_steps=64)
{'headroom': 1.5, 'max_time_s': None}
>>> check_options({"cfar_range": True})
Traceback (most recent call last):
...
ir.errors.CompileError: compile option cfar_range=True must be a pair (lo, hi) of finite \
numbers, or a mapping of node id to one
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from pydantic import BaseModel, ValidationError

from compiler.lowering.options import MOTIF_OPTION_MODELS
from compiler.passes.static_split import StaticSplitOptions
from ir.errors import CompileError
from ir.model import short_repr

__all__ = ["OPTION_CHECKS", "check_options", "typed_checks"]


def _real(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _int(v: object) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _pair(v: object) -> bool:
    return isinstance(v, list | tuple) and len(v) == 2 and all(_real(x) for x in v)


def _quantiles(v: object) -> bool:
    return _pair(v) and 0 <= v[0] <= v[1] <= 1


def _per_node(rule: Callable[[object], bool]) -> Callable[[object], bool]:
    return lambda v: rule(v) or (isinstance(v, Mapping) and all(
        isinstance(k, str) and rule(x) for k, x in v.items()))


def _one_of(*names: str) -> Callable[[object], bool]:
    return lambda v: isinstance(v, str) and v in names


def typed_checks(model: type[BaseModel]) -> dict[str, tuple[Callable[[object], bool], str]]:
    """Checkers of the options a pass or motif declares as typed fields of ``model``.

    Each field is one option (its name), validated by pydantic as the field; the field's
    ``description`` says what the value must be.

    Examples
    --------
    >>> from compiler.passes.static_split import StaticSplitOptions
    >>> rule, what = typed_checks(StaticSplitOptions)["static_split"]
    >>> rule("off"), rule("on"), what
    (True, False, 'auto or off')
    """
    def rule(name: str) -> Callable[[object], bool]:
        def ok(value: object) -> bool:
            try:
                model.model_validate({name: value})
            except ValidationError:
                return False
            return True
        return ok

    return {name: (rule(name), f.description or name) for name, f in model.model_fields.items()}


#: Option name -> (rule, what the value must be).
OPTION_CHECKS: dict[str, tuple[Callable[[object], bool], str]] = {
    "headroom": (lambda v: _real(v) and v >= 1, "a finite number >= 1"),
    "input_bounds": (lambda v: isinstance(v, Mapping) and all(
        isinstance(k, str) and _real(x) and x > 0 for k, x in v.items()),
        "a mapping of input node id to a finite number > 0"),
    "fft_radices": (lambda v: isinstance(v, list | tuple) and len(v) >= 1 and all(
        _int(r) and 2 <= r <= 1 << 16 for r in v), "a list of integer radices >= 2"),
    "cfar_range": (_per_node(_pair),
                   "a pair (lo, hi) of finite numbers, or a mapping of node id to one"),
    "cfar_quantiles": (_per_node(_quantiles),
                       "a pair (lo, hi) of quantiles, 0 <= lo <= hi <= 1, or a mapping of node "
                       "id or CFAR kind to one"),
    "long_delays": (_one_of("relay", "error"), "relay or error"),
    "repetitions": (_one_of("auto", "spatial", "temporal"), "auto, spatial or temporal"),
    "frame_rate_hz": (lambda v: _real(v) and v > 0, "a finite number > 0"),
    "real_bits": (lambda v: _int(v) and 1 <= v <= 64, "an integer in 1..64"),
    "n_angle_bins": (lambda v: _int(v) and 1 <= v <= 1 << 20, "an integer in 1..1048576"),
    "time_steps": (lambda v: _int(v) and v >= 1, "an integer >= 1"),
    "weight_bits": (lambda v: _int(v) and 2 <= v <= 64, "an integer in 2..64"),
    "calibration": (lambda v: isinstance(v, str), "static or per-input"),
    "motifs": (lambda v: isinstance(v, Mapping) and all(
        isinstance(k, str) and isinstance(x, str) for k, x in v.items()),
        "a mapping of node id or op name to a motif name"),
    **typed_checks(StaticSplitOptions),
}
# the motifs' typed fields (compiler.lowering.options); the rules above stay where they are
# stricter than pydantic's (no bool or float for an int, ordered quantiles)
OPTION_CHECKS = {**{n: c for m in MOTIF_OPTION_MODELS for n, c in typed_checks(m).items()},
                 **OPTION_CHECKS}


def check_options(options: Mapping[str, Any] | None, **named: Any) -> dict[str, Any]:
    """Refuse an option value its checker rejects; drop the checked options set to ``None``.

    Parameters
    ----------
    options : mapping, optional
        ``compile_graph``'s ``options=``.
    **named
        Its named arguments checked the same way (``time_steps``, ``weight_bits``,
        ``calibration``, ``motifs``).

    Returns
    -------
    dict
        ``options`` without the checked ones set to ``None`` (others, e.g. the
        limits ``max_memory_bytes=None`` = no limit, are kept).

    Raises
    ------
    CompileError
        Naming the option, the value and the rule.
    """
    for name, value in {**dict(options or {}), **named}.items():
        rule = OPTION_CHECKS.get(name)
        if value is None or rule is None:
            continue
        ok, what = rule
        if not ok(value):
            raise CompileError(f"compile option {name}={short_repr(value)} must be {what}")
    return {k: v for k, v in dict(options or {}).items()
            if not (v is None and k in OPTION_CHECKS)}
