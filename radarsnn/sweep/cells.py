"""The id of a sweep cell: the hash of everything that determines its result.

A **cell** is one grid point on one slice of frames; :func:`cell_key` hashes its parts'
canonical JSON, so a re-run skips the cells already done and an edited spec recomputes
exactly the cells it changed.  :class:`CellKey` builds a key a part at a time (a shared
prefix hashed once), :class:`Canonical` holds a part already serialised.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

__all__ = ["Canonical", "CellKey", "cell_key"]


def cell_key(*parts: Any) -> str:
    """16 hex digits of the SHA-256 of the canonical JSON of ``parts``.

    Examples
    --------
    >>> cell_key({"b": 1, "a": [1, 2]}, (0, 25)) == cell_key({"a": [1, 2], "b": 1}, [0, 25])
    True
    >>> len(cell_key("x"))
    16
    """
    return CellKey(*parts).hex()


class Canonical(bytes):
    """A part already in :func:`cell_key`'s canonical JSON (:meth:`Canonical.of`), hashed as
    is: a large part shared by many keys is serialised once."""

    @classmethod
    def of(cls, part: Any) -> Canonical:
        """``part`` serialised as :func:`cell_key` serialises it."""
        return cls(_canonical(part))


def _canonical(part: Any) -> bytes:
    if isinstance(part, Canonical):
        return bytes(part)
    return json.dumps(part, sort_keys=True, separators=(",", ":"), default=str).encode()


class CellKey:
    """:func:`cell_key` built a part at a time: a prefix is serialised and hashed once and
    shared by every key that extends it (the chain, for each of the grid's points).

    ``CellKey(a).then(b, c).hex() == cell_key(a, b, c)``: the hash of the canonical JSON
    list, fed item by item.

    Examples
    --------
    >>> chain = CellKey({"nodes": ["..."]})
    >>> chain.then({"time_steps": 8}, "step").hex() == cell_key({"nodes": ["..."]},
    ...                                                          {"time_steps": 8}, "step")
    True
    >>> CellKey(Canonical.of({"b": 1, "a": 2})).hex() == cell_key({"a": 2, "b": 1})
    True
    """

    def __init__(self, *parts: Any) -> None:
        self._hash, self._empty = hashlib.sha256(b"["), True
        self._add(parts)

    def _add(self, parts: tuple) -> None:
        for part in parts:
            self._hash.update((b"" if self._empty else b",") + _canonical(part))
            self._empty = False

    def then(self, *parts: Any) -> CellKey:
        """A new key: this one's parts, then ``parts`` (this one is unchanged)."""
        other = CellKey.__new__(CellKey)
        other._hash, other._empty = self._hash.copy(), self._empty
        other._add(parts)
        return other

    def hex(self) -> str:
        """16 hex digits, as :func:`cell_key`."""
        done = self._hash.copy()
        done.update(b"]")
        return done.hexdigest()[:16]
