r"""Safe code rendering: templates filled only with literals and validated identifiers.

Every piece of generated code is a :class:`Code`.  A ``Code`` can only come
from :func:`lit` (a plain number, bool, ``None``, a string as a single-quoted
literal of printable ASCII with every quote, backslash and other character escaped,
or a tuple of those), :func:`ident` (a name matching ``[A-Za-z_][A-Za-z0-9_]*`` that
is not a keyword), :func:`render` (a template whose ``$fields`` are all
``Code``) or :func:`join`.  A raw ``str`` is refused wherever code is
expected, so a node id, a name or metadata from a chain file can only ever
appear inside a string literal or a comment built by :func:`comment`, never
in a code position.

Templates are :class:`string.Template` texts: the files of
``backends/emit/templates/`` (:func:`template`) or short inline ones.  Deliberately
not a template engine such as Jinja2: its expressions, filters and loops would let
a template compute text outside the :class:`Code` discipline (and its autoescaping
is for HTML, not Python); with ``$field`` substitution only, every character a
template adds is either its own text or a checked ``Code``, and the structure of
the generated code (loops over populations, branches per phase) stays in typed
Python (:mod:`backends.emit.numpy_network`).

Examples
--------
>>> print(render("x = $value  # $note", value=lit(0.5), note=comment("a'b\nc")))
x = 0.5  # 'a\x27b\nc'
>>> print(lit("__import__('os')"))
'__import__(\x27os\x27)'
>>> ident("not valid")
Traceback (most recent call last):
ir.errors.CompileError: generated name 'not valid' is not a valid Python identifier
"""

from __future__ import annotations

import keyword
import math
import re
from functools import cache
from importlib import resources
from string import Template

from ir.errors import CompileError

__all__ = ["Code", "lit", "ident", "comment", "join", "render", "template", "indent"]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: Longest chunk of a string literal on one line (longer strings are split over lines).
_CHUNK = 50


class Code:
    """A fragment of generated Python source (only made by this module's functions)."""

    __slots__ = ("text",)

    def __init__(self, text: str, _token: object = None) -> None:
        if _token is not _SECRET:
            raise TypeError("Code is made by lit(), ident(), comment(), join() or render()")
        self.text = text

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        return f"Code({self.text!r})"


_SECRET = object()


def _code(text: str) -> Code:
    return Code(text, _SECRET)


def _literal(value: object) -> str:
    if value is None or isinstance(value, bool):
        return repr(value)
    if isinstance(value, int):
        return repr(int(value))
    if isinstance(value, float):
        if math.isnan(value):
            return 'float("nan")'
        if math.isinf(value):
            return 'float("inf")' if value > 0 else '-float("inf")'
        return repr(float(value))
    if isinstance(value, str):
        text = _quote(value)
        if len(text) <= _CHUNK + 2:
            return text
        return "(\n" + "\n".join(f"    '{p}'" for p in _chunks(text[1:-1])) + "\n)"
    if isinstance(value, tuple):
        items = [_literal(v) for v in value]
        flat = "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"
        if len(flat) <= _CHUNK or "\n" in flat and len(items) == 1:
            return flat
        return "(\n" + "".join(f"    {item},\n" for item in items) + ")"
    raise CompileError(f"cannot emit a literal of type {type(value).__name__}: only None, bool, "
                       "int, float, str and tuples of them are written into generated code")


def _quote(text: str) -> str:
    r"""``text`` as a single-quoted literal of printable ASCII without quotes or backslashes.

    Every character outside ``[ -~]``, and ``'``, ``"`` and ``\``, is written as an escape
    (``\x27``, ``\n``, ``\u202e``...), so the literal cannot close a string or a
    docstring it is placed in, nor end a comment line.

    Examples
    --------
    >>> print(_quote("a'\"b\\\n\u00e9"))
    'a\x27\x22b\x5c\n\xe9'
    """
    return "'" + "".join(_ESCAPES.get(c) or (c if " " <= c <= "~" else ascii(c)[1:-1])
                         for c in text) + "'"


def _chunks(body: str) -> list[str]:
    """``body`` (an escaped literal's inside) cut into pieces of about ``_CHUNK`` characters,
    never inside an escape."""
    pieces = re.findall(r"\\(?:x..|u....|U........|.)|[^\\]", body)
    out, cur = [], ""
    for piece in pieces:
        if len(cur) + len(piece) > _CHUNK:
            out.append(cur)
            cur = ""
        cur += piece
    return [*out, cur]


_ESCAPES = {"'": "\\x27", '"': "\\x22", "\\": "\\x5c"}


def lit(value: object) -> Code:
    r"""A Python literal of ``value``, via ``ascii()`` / ``repr()`` of plain data.

    Parameters
    ----------
    value : None, bool, int, float, str or tuple of those
        numpy scalars must be converted first (``float(x)``, ``int(x)``).

    Returns
    -------
    Code

    Raises
    ------
    CompileError
        For any other type.

    Examples
    --------
    >>> print(*(lit(x) for x in (1, 2.5, float("-inf"), "é", (3,))))
    1 2.5 -float("inf") '\xe9' (3,)
    """
    return _code(_literal(value))


def ident(name: str) -> Code:
    """A validated identifier.

    Raises
    ------
    CompileError
        If ``name`` is not an ASCII identifier or is a keyword.

    Examples
    --------
    >>> str(ident("stage_rng"))
    'stage_rng'
    """
    if not (isinstance(name, str) and _IDENT.fullmatch(name) and not keyword.iskeyword(name)):
        raise CompileError(f"generated name {name!r} is not a valid Python identifier")
    return _code(name)


def comment(text: str, limit: int = 60) -> Code:
    r"""An ASCII literal of ``text`` for use after ``#``, cut to ``limit`` characters.

    Newlines, quotes, backslashes and every non-ASCII character are escaped, so the
    comment cannot end early (a cut inside an escape only shortens the comment).
    Comments never reach lines 1-2 of a generated file (whose text is fixed), so no
    user text can be read as a PEP 263 ``coding:`` declaration.

    Examples
    --------
    >>> print(comment("line\nbreak"))
    'line\nbreak'
    """
    text = _quote(str(text))
    return _code(text if len(text) <= limit else text[:limit] + "...")


def join(parts: list[Code], sep: str = "\n") -> Code:
    """Concatenate fragments with a fixed separator (newlines, ``", "`` or nothing).

    Examples
    --------
    >>> str(join([lit(1), lit(2)], ", "))
    '1, 2'
    """
    if sep not in ("\n", ", ", "", "\n\n", "\n\n\n"):
        raise CompileError(f"join separator {sep!r} is not one of the fixed separators")
    for p in parts:
        _check(p, "join")
    return _code(sep.join(p.text for p in parts))


def indent(code: Code, levels: int = 1) -> Code:
    """Indent every non-empty line by four spaces per level.

    Examples
    --------
    >>> str(indent(lit(1), 2))
    '        1'
    """
    _check(code, "indent")
    pad = "    " * levels
    return _code("\n".join(pad + ln if ln else ln for ln in code.text.split("\n")))


def _check(value: object, field: str) -> None:
    if not isinstance(value, Code):
        raise CompileError(f"template field {field!r} got a raw {type(value).__name__}; only "
                           "lit(), ident(), comment(), join() or render() values are allowed")


@cache
def template(name: str) -> str:
    """The text of ``backends/emit/templates/<name>``.

    Examples
    --------
    >>> template("stage.py.tmpl").startswith("$header")
    True
    """
    if not re.fullmatch(r"[a-z_]+(\.py)?\.tmpl", name):
        raise CompileError(f"bad template name {name!r}")
    return resources.files("backends.emit").joinpath("templates", name).read_text("utf-8")


def render(text: str, **fields: Code) -> Code:
    """Fill a template's ``$fields``; every value must be a :class:`Code`.

    Parameters
    ----------
    text : str
        Template text (from :func:`template` or a constant in the emitter).
    **fields : Code

    Returns
    -------
    Code

    Raises
    ------
    CompileError
        For a raw value or a missing field.

    Examples
    --------
    >>> str(render("f($a)", a=lit("x")))
    "f('x')"
    >>> render("f($a)", a="x")
    Traceback (most recent call last):
    ir.errors.CompileError: template field 'a' got a raw str; only lit(), ident(), comment(), \
join() or render() values are allowed
    """
    for key, value in fields.items():
        _check(value, key)
    try:
        return _code(Template(text).substitute({k: v.text for k, v in fields.items()}))
    except (KeyError, ValueError) as exc:
        raise CompileError(f"template field missing or malformed: {exc}") from exc
