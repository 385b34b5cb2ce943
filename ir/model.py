"""The pydantic base of every IR record (tensor types and ops), and name rules.

Every IR record is a frozen pydantic model that forbids unknown fields. Building
one with bad values raises :class:`~ir.errors.IRError` (not pydantic's
``ValidationError``), naming the record and each offending field, so callers
catch one exception hierarchy.

Examples
--------
>>> from ir.model import IRModel
>>> class Point(IRModel):
...     x: int
>>> Point(x=1)
Point(x=1)
>>> try:
...     Point(x="one")
... except IRError as err:
...     print(err)
Point: field 'x': Input should be a valid integer, unable to parse string as an integer (got 'one')
"""

from __future__ import annotations

import re
import reprlib
from typing import Annotated, Any, ClassVar

from pydantic import BaseModel, ConfigDict, StringConstraints, ValidationError

from ir.errors import CompileValidationError, IRError, NetworkValidationError

__all__ = ["NAME_PATTERN", "CheckedModel", "IRModel", "Name", "describe_validation_error",
           "is_name", "short_repr"]

NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_\-]*$"
"""Node ids and axis names: a letter or ``_``, then letters, digits, ``_`` or ``-``."""

Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN)]
"""A node id or axis name (see :data:`NAME_PATTERN`)."""

_NAME_RE = re.compile(NAME_PATTERN)


def describe_validation_error(err: ValidationError) -> str:
    """One line per problem of a pydantic ``ValidationError``: field, reason, value.

    Parameters
    ----------
    err : pydantic.ValidationError
        The error to describe.

    Returns
    -------
    str
        ``"field 'a.b': <reason> (got <value>)"`` entries joined by ``"; "``;
        problems not tied to one field read ``"<reason>"``.

    Examples
    --------
    >>> from pydantic import BaseModel, ValidationError
    >>> class M(BaseModel):
    ...     n: int
    >>> try:
    ...     M(n="x")
    ... except ValidationError as err:
    ...     print(describe_validation_error(err))
    field 'n': Input should be a valid integer, unable to parse string as an integer (got 'x')
    """
    items = [
        (tuple(str(p) for p in item["loc"] if not _is_union_tag(p)), item)
        for item in err.errors(include_url=False)
    ]
    locs = {loc for loc, _ in items}
    parts: dict[tuple[str, ...], str] = {}
    for loc, item in items:
        # Union members fail together: keep the first reason per field, and prefer the
        # member that got furthest (a deeper location) over a bare type mismatch.
        if loc in parts or any(o[: len(loc)] == loc and len(o) > len(loc) for o in locs):
            continue
        reason = item["msg"].removeprefix("Value error, ")
        got = "" if item["type"] == "missing" else f" (got {short_repr(item.get('input'))})"
        parts[loc] = f"field {'.'.join(loc)!r}: {reason}{got}" if loc else reason
    return "; ".join(parts.values())


_UNION_TAGS = frozenset({"int", "float", "str", "bool", "none", "list", "tuple", "dict"})


def _is_union_tag(part: object) -> bool:
    """Whether a location part names a union member (``"int"``, ``"tuple[int, ...]"``)."""
    return isinstance(part, str) and (
        "[" in part or part in _UNION_TAGS or part.startswith("constrained-")
    )


class _BoundedRepr(reprlib.Repr):
    """``reprlib`` limits (3 levels, 6 items, 60 characters) and no full ``repr`` of big ints."""

    def __init__(self) -> None:
        super().__init__()
        self.maxlevel = 3
        self.maxtuple = self.maxlist = self.maxarray = self.maxdict = 6
        self.maxset = self.maxfrozenset = self.maxdeque = 6
        self.maxstring = self.maxother = self.maxlong = 60

    def repr_int(self, x: int, level: int) -> str:
        if x.bit_length() > 192:  # str(int) is quadratic and refused past 4300 digits
            return f"<{'-' if x < 0 else ''}int of {x.bit_length()} bits>"
        return super().repr_int(x, level)

    def repr_instance(self, x: object, level: int) -> str:
        try:
            return super().repr_instance(x, level)
        except Exception:  # noqa: BLE001 - a broken __repr__ must not hide the real error
            return f"<{type(x).__name__}>"


_BOUNDED_REPR = _BoundedRepr()


def short_repr(value: Any, limit: int = 60) -> str:
    """A ``repr`` of ``value`` of at most ``limit`` characters, in bounded time and memory.

    Error messages quote the values they refuse; a value read from a file may be huge
    (a long list, a deeply nested or alias-shared structure whose full ``repr`` is
    gigabytes), so it is rendered item by item with :mod:`reprlib`'s limits (three
    levels, six items per container) before it is cut to ``limit``: the full ``repr``
    is never built.

    Examples
    --------
    >>> short_repr({"a": list(range(100))})
    "{'a': [0, 1, 2, 3, 4, 5, ...]}"
    >>> shared = [1]
    >>> for _ in range(200):  # 2**200 leaves if expanded
    ...     shared = [shared, shared]
    >>> short_repr(shared)
    '[[[[...], [...]], [[...], [...]]], [[[...], [...]], [[......'
    >>> short_repr(10**5000)
    '<int of 16610 bits>'
    """
    text = _BOUNDED_REPR.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def is_name(text: object) -> bool:
    """Whether ``text`` is a valid node id / axis name.

    Examples
    --------
    >>> is_name("range"), is_name("2nd"), is_name("a b")
    (True, False, False)
    """
    return isinstance(text, str) and _NAME_RE.match(text) is not None


class IRModel(BaseModel):
    """Frozen pydantic record whose construction errors are :class:`IRError`.

    Raises
    ------
    IRError
        When a field is missing, unknown, of the wrong type or out of range;
        the message names the record class and every bad field.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as err:
            raise IRError(f"{self.describe_kind()}: {describe_validation_error(err)}") from err

    @classmethod
    def describe_kind(cls) -> str:
        """How errors name this kind of record (the class name by default)."""
        return cls.__name__


class CheckedModel(BaseModel):
    """Pydantic model whose construction errors are typed radarsnn errors.

    A subclass names its error class in ``error_class``
    (:class:`~ir.errors.NetworkValidationError` or
    :class:`~ir.errors.CompileValidationError`); building it with a bad value raises
    that class, which is also a pydantic ``ValidationError``, with a message naming the
    record, each bad field, the rule it breaks and the value given; ``model_validate``
    raises it too, and a nested record's problems are listed under its field.

    Raises
    ------
    NetworkValidationError or CompileValidationError
        When a field is missing, unknown, of the wrong type or out of range.

    Examples
    --------
    >>> from ir.errors import NetworkError
    >>> class Cell(CheckedModel):
    ...     error_class = NetworkValidationError
    ...     size: int
    >>> try:
    ...     Cell(size=[1])
    ... except NetworkError as err:
    ...     print(err)
    Cell: field 'size': Input should be a valid integer (got [1])
    """

    error_class: ClassVar[type[NetworkValidationError] | type[CompileValidationError]]

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as err:
            raise self._typed(err) from None

    @classmethod
    def model_validate(cls, obj: Any, **kwargs: Any) -> Any:
        """Pydantic's ``model_validate``, raising ``error_class`` like the constructor.

        A mapping's non-string key (a YAML ``1: 1``) can name no field: it is passed on as
        its text, so it is refused as an unknown field instead of a ``TypeError`` of the
        keyword call.
        """
        if isinstance(obj, dict) and not all(isinstance(k, str) for k in obj):
            obj = {k if isinstance(k, str) else str(k): v for k, v in obj.items()}
        try:
            return super().model_validate(obj, **kwargs)
        except ValidationError as err:
            raise cls._typed(err) from None

    @classmethod
    def _typed(cls, err: ValidationError) -> ValidationError:
        """``err`` as ``error_class`` (unchanged if it already is a radarsnn error)."""
        if isinstance(err, cls.error_class):
            return err
        return cls.error_class.of(err, f"{cls.__name__}: {describe_validation_error(err)}")
