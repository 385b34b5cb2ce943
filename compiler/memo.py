r"""Work a measured compile does once: the memo its attempts share.

A measured compile (``compile_graph`` with a simulator, :mod:`compiler.accuracy.select`)
compiles the same chain several times with different motifs.  Much of each attempt is the
same work on the same inputs: the time-coded DFT's weights rounded against the same
calibrated second moment, and — where a spiking segment comes out the same — splitting
that network into blocks, counting its blocks' fan-in, and building its simulation plan.
One :class:`CompileMemo`, made by the measured compile and handed to every attempt's
:class:`~compiler.passes.CompileContext` (never a module-level cache), keeps each such
result for the attempts after it:

* :meth:`CompileMemo.rint_feedback` — :func:`compiler.quantize_weights.rint_feedback` of
  equal arguments (compared by content) is computed once, and so is any array made from
  arrays alone (:meth:`CompileMemo.of_arrays`: a DFT layer's real weight matrix);
* :meth:`CompileMemo.network` — a quantized network equal in content to one an earlier
  attempt built (:func:`network_digest`) is replaced by that earlier object, so whatever
  is kept per network object (its blocks' demand, :mod:`compiler.hardware.demand`; the
  reference simulator's plans) is reused;
* :meth:`CompileMemo.split` — the split of the same network object under the same
  profile and multiplexed stages is computed once;
* :meth:`CompileMemo.kept` — any other result of the same objects and values, e.g. a
  network's spike traffic when its blocks sit on the same cores
  (:func:`compiler.passes.place_traffic.spike_traffic`).

Every result is the one the work would produce again: the memo changes how often the work
is done, never what it gives (a compile with a memo and one without give byte-identical
programs).

Examples
--------
>>> import numpy as np
>>> memo = CompileMemo()
>>> x, h = np.array([[0.4], [0.4]]), np.ones((2, 2))
>>> memo.rint_feedback(x, h, 127).ravel().tolist()
[0.0, 1.0]
>>> memo.rint_feedback(x.copy(), h.copy(), 127) is memo.rint_feedback(x, h, 127)
True
>>> from compiler.snn.examples import tiny_network
>>> a, b = tiny_network(n_steps=4), tiny_network(n_steps=4)
>>> memo.network(a) is a, memo.network(b) is a, memo.network(tiny_network(n_steps=5)) is a
(True, True, False)
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import BaseModel

from compiler.quantize_weights import rint_feedback
from compiler.snn import SpikingNetwork

__all__ = ["CompileMemo", "network_digest"]


class _Opaque(TypeError):
    """A value :func:`_feed` cannot digest by content."""


def _feed(h, obj: Any) -> None:
    """Feed ``obj``'s content, tagged with its type, into the hash ``h`` (order kept)."""
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"A{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif obj is None or isinstance(obj, (bool, int, float, complex, str, np.generic)):
        h.update(f"{type(obj).__qualname__}:{obj!r};".encode())
    elif isinstance(obj, BaseModel):
        h.update(f"M{type(obj).__module__}.{type(obj).__qualname__}(".encode())
        for name in type(obj).model_fields:
            h.update(f"{name}=".encode())
            _feed(h, getattr(obj, name))
        h.update(b")")
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"D{type(obj).__module__}.{type(obj).__qualname__}(".encode())
        for f in dataclasses.fields(obj):
            h.update(f"{f.name}=".encode())
            _feed(h, getattr(obj, f.name))
        h.update(b")")
    elif isinstance(obj, dict):  # insertion order is part of the content (axis order)
        h.update(f"d{len(obj)}{{".encode())
        for k, v in obj.items():
            _feed(h, k)
            _feed(h, v)
        h.update(b"}")
    elif isinstance(obj, (list, tuple, frozenset, set)):
        items = sorted(obj, key=repr) if isinstance(obj, (set, frozenset)) else obj
        h.update(f"{type(obj).__qualname__}{len(obj)}[".encode())
        for v in items:
            _feed(h, v)
        h.update(b"]")
    else:
        raise _Opaque(type(obj).__qualname__)


def network_digest(network: SpikingNetwork) -> str | None:
    """A SHA-256 of everything ``network`` holds (its name, steps, parts with their arrays,
    and meta), or None when a part holds a value not digestible by content.

    Examples
    --------
    >>> from compiler.snn.examples import tiny_network
    >>> network_digest(tiny_network(n_steps=4)) == network_digest(tiny_network(n_steps=4))
    True
    >>> network_digest(tiny_network(n_steps=4)) == network_digest(tiny_network(n_steps=6))
    False
    """
    h = hashlib.sha256()
    try:
        _feed(h, network)
    except _Opaque:
        return None
    return h.hexdigest()


def _arrays_key(*arrays: np.ndarray) -> str:
    h = hashlib.sha256()
    for a in arrays:
        _feed(h, np.asarray(a))
    return h.hexdigest()


@dataclass
class CompileMemo:
    """Results the attempts of one measured compile share (see the module docstring).

    Attributes
    ----------
    hits : dict of str to int
        How often each kind of work was reused (``rint_feedback``, ``network``, ``split``,
        ``traffic``, and each kind given to :meth:`kept` or :meth:`of_arrays`, such as
        ``real_weights``).
    """

    hits: dict[str, int] = field(default_factory=lambda: {"rint_feedback": 0, "network": 0,
                                                          "split": 0, "traffic": 0})
    _rounded: dict[tuple, np.ndarray] = field(default_factory=dict, repr=False)
    _networks: dict[str, SpikingNetwork] = field(default_factory=dict, repr=False)
    _kept: dict[tuple, Any] = field(default_factory=dict, repr=False)

    def rint_feedback(self, x: np.ndarray, h: np.ndarray, w_max: float) -> np.ndarray:
        """:func:`~compiler.quantize_weights.rint_feedback` ``(x, h, w_max)``, computed once
        per content of its arguments (the result is read-only)."""
        key = (_arrays_key(x, h), float(w_max))
        found = self._rounded.get(key)
        if found is not None:
            self.hits["rint_feedback"] += 1
            return found
        out = rint_feedback(x, h, w_max)
        out.setflags(write=False)
        self._rounded[key] = out
        return out

    def of_arrays(self, kind: str, arrays: tuple[np.ndarray, ...], key: Any,
                  compute: Callable[[], np.ndarray]) -> np.ndarray:
        """``compute()`` — an array made from ``arrays`` and ``key`` alone — once per
        content of ``arrays`` and ``key`` (the result is read-only)."""
        def made() -> np.ndarray:
            out = compute()
            out.setflags(write=False)
            return out
        return self.kept(kind, (), (_arrays_key(*arrays), key), made)

    def network(self, network: SpikingNetwork) -> SpikingNetwork:
        """The first network seen equal in content to ``network`` (``network`` itself when
        none was, or when it cannot be digested)."""
        digest = network_digest(network)
        if digest is None:
            return network
        found = self._networks.setdefault(digest, network)
        if found is not network:
            self.hits["network"] += 1
        return found

    def split(self, network: SpikingNetwork, profile: Any, multiplexed: Collection[str],
              compute: Callable[[], Any]) -> Any:
        """``compute()`` — the split of ``network`` for ``profile`` with ``multiplexed``
        stages (these objects) — once per such triple."""
        return self.kept("split", (network, profile), tuple(sorted(multiplexed)), compute)

    def kept(self, kind: str, owners: tuple, key: Any, compute: Callable[[], Any]) -> Any:
        """``compute()`` once per ``kind``, ``owners`` (these objects: a network, its
        split record…) and ``key`` (hashable values); later calls return the same result."""
        full = (kind, tuple(id(o) for o in owners), key)
        held = self._kept.get(full)
        if held is not None and all(a is b for a, b in zip(held[0], owners, strict=True)):
            self.hits[kind] = self.hits.get(kind, 0) + 1  # the ids are still their own
            return held[1]
        value = compute()
        self._kept[full] = (owners, value)
        return value
