r"""The out-of-range policy of the encoders: find values a code cannot represent, then
refuse them or clip them on request.

An encoder's code represents the values in ``[x_min, x_max]`` (its *range*, set
by calibration).  Values above it saturate: a latency code would have to spike
before its window opens, a rate code faster than its top rate, and the code
clips them.  A value is *out of range* when clipping changes its spikes:

.. math::

    \text{latency:}\quad x > x^{*} = \mathrm{value\_of}(t_{min} - \tfrac12)
    \ (\text{nearest rounding}), \quad x > x_{max}\ (\text{floor rounding}),\qquad
    \text{rate:}\quad \lfloor T r(x) + \varphi\rfloor > \lfloor T r_{max} + \varphi\rfloor

(``value_of`` extrapolates the code's linear or log map; a value within half a
step above ``x_max`` spikes at ``t_min`` exactly like ``x_max``, so it loses
nothing).  Values below ``x_min`` are the code's *floor*: they read as "no spike"
(latency) or rate 0, like ``x_min`` itself, by the code's definition.  A code whose
window is one step (``t_max - t_min = 1``) is a threshold — every value has its
one-bit meaning — and is never out of range.  ``NaN`` and ``±Inf`` are refused
before this check under every policy.

The check runs on the encoded parts (after per-input normalisation and the
signed/complex split); a value counts once however many of its parts are out.

Policies (:data:`POLICIES`): ``"reject"`` (the default, :data:`DEFAULT_POLICY`)
raises :class:`~ir.errors.SimulationError` naming the port, the count, the first
index, its value, the range and the ways out; ``"warn"`` lets the code clip them and
warns with the same facts (:class:`OutOfRangeWarning`); ``"clip"`` clips without a
warning.  Under ``warn`` and ``clip`` the caller reports the count
(``SimResult.clipped``), so out-of-range values are never propagated into spike
times silently.

Clipping is a request, not a default: the compiler's default calibration has no
headroom (option ``headroom=1``), so a program calibrated on one frame and run on
another may see a few values above its range.  Calibrate on data that covers them,
compile with ``options={"headroom": 1.1}`` (input encoders; ``cfar_range`` sets a CFAR
code's range), or pass ``out_of_range="clip"``
(``radarsnn run --clip``; a generated package's ``run(..., out_of_range="clip")``
or ``--clip``).

Examples
--------
>>> import numpy as np
>>> from compiler.snn import LatencyCode
>>> code = LatencyCode(t_max=8, x_min=0.0, x_max=1.0)   # one step = 1/8; x* = 1.0625
>>> parts = np.array([[0.5, 1.05, -0.25, 2.0, 1.07]])     # (frames, values), split "none"
>>> out_of_range(code, parts, n_parts=0, n_steps=8).tolist()
[[False, False, False, True, True]]
>>> check_range("x", code, parts, n_parts=0, n_steps=8, framed=False, policy="clip")
2
>>> check_range("x", code, parts, n_parts=0, n_steps=8, framed=False,
...             policy="reject")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ir.errors.SimulationError: input 'x': 2 of 5 values are above the encoder's range [0, 1] ...
"""

from __future__ import annotations

import warnings

import numpy as np

from compiler.snn.coding import LatencyCode, RateCode
from ir.errors import SimulationError

__all__ = ["DEFAULT_POLICY", "FIXES", "PER_PART", "POLICIES", "OutOfRangeWarning",
           "check_policy", "check_range", "out_of_range"]

#: What :func:`check_range` does with values outside a code's range.
POLICIES = ("reject", "warn", "clip")
#: The policy of :func:`~backends.reference.simulate`, ``run_program`` and ``encode_inputs``
#: unless told (``radarsnn run`` and generated packages too).
DEFAULT_POLICY = "reject"
#: The ways out named by the error and the warning.
FIXES = ("calibrate on data that covers them (or widen the range: compile option headroom, "
         "e.g. 1.1, or cfar_range for a CFAR's input), or clip them on request: "
         "out_of_range='clip' (Python), --clip (radarsnn run)")
#: What the range applies to, per encoder split (a signed split codes magnitudes per sign).
PER_PART: dict[str, str] = {
    "none": "", "re_im": " (per real and imaginary part)", "signed": " (per sign: |x|)",
    "re_im_signed": " (per sign of the real and imaginary parts: |Re x|, |Im x|)"}


class OutOfRangeWarning(UserWarning):
    """Input values above an encoder's range were clipped (policy ``"warn"``)."""


def check_policy(policy: object, where: str) -> str:
    """``policy`` if it is one of :data:`POLICIES`, else a :class:`SimulationError`.

    Examples
    --------
    >>> check_policy("clip", "network 'n'")
    'clip'
    >>> check_policy("wrap", "network 'n'")
    Traceback (most recent call last):
    ...
    ir.errors.SimulationError: network 'n': out_of_range='wrap' is not one of ('reject', 'warn', \
'clip')
    """
    if not isinstance(policy, str) or policy not in POLICIES:
        raise SimulationError(f"{where}: out_of_range={policy!r} is not one of {POLICIES}")
    return policy


def out_of_range(code: LatencyCode | RateCode, parts: np.ndarray, n_parts: int,
                 n_steps: int) -> np.ndarray:
    """Which values (not parts) clipping would change (see the module for the rule).

    Parameters
    ----------
    code : LatencyCode or RateCode
        The encoder's code.
    parts : ndarray
        Encoded parts, ``(frames, *value_shape)`` plus a trailing part axis when
        ``n_parts > 0``; finite.
    n_parts : int
        Size of the trailing part axis (0: no part axis).
    n_steps : int
        Steps of the network (the window of a rate code).

    Returns
    -------
    ndarray of bool
        ``(frames, *value_shape)``: True where some part is out of range.
    """
    if code.type == "stream":
        bad = parts > code.bound()
    elif code.type == "latency":
        if code.t_max - code.t_min <= 1:  # a threshold: every value has its meaning
            bad = np.zeros(parts.shape, bool)
        elif code.rounding in ("floor", "dither"):  # dither: floor(t + u), u may be 0
            bad = parts > code.x_max
        else:
            edge = code.t_min - 0.5
            bound = float(code.value_of(np.array(edge)))
            bad = parts > bound
            if np.rint(edge) < code.t_min:  # the bound itself rounds to before t_min
                bad |= parts == bound
    else:
        rate = code.max_rate * (parts - code.x_min) / (code.x_max - code.x_min)
        bad = np.floor(n_steps * rate + code.phase) > np.floor(n_steps * code.max_rate
                                                               + code.phase)
    if not n_parts:
        return bad
    if n_parts in (2, 4, 8) and bad.flags.c_contiguous:  # the parts' flags as one word each
        return bad.view(f"u{n_parts}")[..., 0] != 0
    return bad.any(axis=-1)


def check_range(port: str, code: LatencyCode | RateCode, parts: np.ndarray, *, n_parts: int,
                n_steps: int, framed: bool, policy: str, values: np.ndarray | None = None,
                split: str = "none") -> int:
    """Apply the out-of-range policy to one port's encoded parts.

    Parameters
    ----------
    port : str
        The encoder port (named in the error).
    code : LatencyCode or RateCode
        Its code.
    parts : ndarray
        As for :func:`out_of_range`.
    n_parts, n_steps : int
        As for :func:`out_of_range`.
    framed : bool
        Whether the caller's array had a frames axis (it is then part of the index).
    policy : {"reject", "warn", "clip"}
        Refuse (``reject``); or accept (the codes clip), warn (``warn`` only) and
        return the count.
    values : ndarray, optional
        The values as given, ``(frames, *value_shape)``, to quote the first one
        (default: the first offending part).
    split : str
        The encoder's split (the message says what the range applies to).

    Returns
    -------
    int
        How many values are out of range (0 under ``reject``, which raises).

    Raises
    ------
    SimulationError
        Under ``reject`` when any value is out of range: the port, the count, the
        first index (frames first iff ``framed``), its value, the range and the
        ways out (:data:`FIXES`).

    Warns
    -----
    OutOfRangeWarning
        Under ``warn``, with the same facts.
    """
    if code.type == "stream" and (not parts.size or np.max(parts) <= code.bound()):
        return 0  # (finite parts) none above the bound: no flags built
    bad = out_of_range(code, parts, n_parts, n_steps)
    count = int(np.count_nonzero(bad))
    if count == 0 or policy == "clip":
        return count
    first = tuple(int(i) for i in np.argwhere(bad)[0])
    index = first if framed else first[1:]
    value = values[first] if values is not None else np.ravel(parts[first])[0]
    facts = (f"input {port!r}: {count} of {bad.size} values are above the encoder's range "
             f"[{code.x_min:.6g}, {code.x_max:.6g}]{PER_PART[split]} by more than its "
             f"resolution (clipping changes their spikes), first at index {index} (value "
             f"{_quote(value)})")
    if policy == "warn":
        warnings.warn(f"{facts}; clipped them (out_of_range='warn'); {FIXES}",
                      OutOfRangeWarning, stacklevel=4)
        return count
    raise SimulationError(f"{facts}; {FIXES}", node=port)


def _quote(value: object) -> str:
    v = complex(value) if np.iscomplexobj(value) else float(value)
    return f"{v:.6g}"
