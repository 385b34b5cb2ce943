"""Plans kept per network: :func:`~backends.reference.simulate` builds each one once.

Building a :class:`~backends.reference.plan.SimPlan` (index maps, stencil edges, factored
weight cores) costs several times what simulating one frame in closed form does, so a
caller that runs a network — or a program, :func:`~backends.reference.run_program` —
frame after frame must not rebuild it per call.  :func:`cached_plan` keeps one plan per
network and arithmetic *on the network itself*, so the plans are freed with the network,
at once (no reference cycle for the garbage collector to find later: what is kept is the
plan without its ``network`` field, and a caller gets it joined to the network — the same
object for as long as anyone holds it).  A table of plans held anywhere else would keep
every network ever run alive, since a plan refers to its network.  A copy of a network
(``copy.copy``, ``copy.deepcopy``, ``dataclasses.replace``) starts without plans.

A cached plan is reused only while the network holds the *same* parts it was built
from: the same step count and the same population, projection, encoder and decoder
objects (compared by identity; each is an immutable record).  Replacing any of them —
``net.projections = [...]``, ``net.n_steps = 16`` — builds a new plan on the next call.
A weight array changed in place is not seen (as with a plan passed explicitly); call
:func:`forget_plan` after doing that.

Examples
--------
>>> from compiler.snn.examples import tiny_network
>>> net = tiny_network(n_steps=4)
>>> peek_plan(net, "float64") is None
True
>>> plan = cached_plan(net, "float64")
>>> cached_plan(net, "float64") is plan, peek_plan(net, "float64") is plan
(True, True)
>>> net.n_steps = 6                      # a changed part: a new plan on the next call
>>> peek_plan(net, "float64") is None, cached_plan(net, "float64") is plan
(True, False)
"""

from __future__ import annotations

import dataclasses
import threading
import weakref

from backends.reference.plan import SimPlan, build_plan
from compiler.snn.network import SpikingNetwork

__all__ = ["cached_plan", "forget_plan", "peek_plan"]

_LOCK = threading.Lock()
#: The attribute of a network that holds its :class:`_Shelf`.
_ATTR = "_radarsnn_plans"
_PORTS = ("populations", "projections", "encoders", "decoders")


class _Shelf:
    """A network's plans: its parts when they were built, ``{arithmetic: plan}`` with
    ``network=None`` (``bare``), the plans handed out (``joined``, weakly), and the lock held
    while one is built.  Never copied: a copy of the network starts empty."""

    __slots__ = ("owner", "parts", "bare", "joined", "building")

    def __init__(self, owner: int = 0) -> None:
        self.owner = owner  # id() of the network it was made for (a shallow copy shares it)
        self.parts: tuple | None = None
        self.bare: dict[str, SimPlan] = {}
        self.joined: dict[str, weakref.ref] = {}
        self.building = threading.Lock()

    def clear(self, parts: tuple | None = None) -> None:
        self.parts, self.bare, self.joined = parts, {}, {}

    def plan(self, network: SpikingNetwork, arithmetic: str) -> SimPlan | None:
        """The kept plan joined to ``network`` (the one handed out before while it lives)."""
        ref = self.joined.get(arithmetic)
        plan = ref() if ref is not None else None
        if plan is None and arithmetic in self.bare:
            plan = dataclasses.replace(self.bare[arithmetic], network=network)
            self.joined[arithmetic] = weakref.ref(plan)
        return plan

    def keep(self, plan: SimPlan) -> SimPlan:
        """Keep ``plan`` (its ``network`` left out) and hand it out."""
        self.bare[plan.arithmetic] = dataclasses.replace(plan, network=None)
        self.joined[plan.arithmetic] = weakref.ref(plan)
        return plan

    def __deepcopy__(self, memo: dict) -> _Shelf:  # the plans are not copied with the network
        return _Shelf()

    def __reduce__(self) -> tuple:
        return _Shelf, ()


def _shelf(net: SpikingNetwork, create: bool) -> _Shelf | None:
    """``net``'s shelf (made on first use when ``create``; one found in a shallow copy's
    attributes belongs to the original and is not used)."""
    with _LOCK:
        shelf = net.__dict__.get(_ATTR)
        if shelf is not None and shelf.owner != id(net):
            shelf = None
        if shelf is None and create:
            shelf = net.__dict__[_ATTR] = _Shelf(id(net))
        return shelf


def _parts(net: SpikingNetwork) -> tuple:
    """What a plan depends on: the step count and the part objects themselves."""
    return (net.n_steps, *(tuple(getattr(net, name)) for name in _PORTS))


def _same(a: tuple | None, b: tuple) -> bool:
    """Whether two :func:`_parts` tuples have equal step counts and the same objects."""
    return a is not None and a[0] == b[0] and all(
        len(x) == len(y) and all(u is v for u, v in zip(x, y, strict=True))
        for x, y in zip(a[1:], b[1:], strict=True))


def peek_plan(network: SpikingNetwork, arithmetic: str) -> SimPlan | None:
    """The cached plan of ``network`` if there is a current one (never builds one)."""
    shelf = _shelf(network, create=False)
    if shelf is None:
        return None
    with _LOCK:
        if not _same(shelf.parts, _parts(network)):
            return None
        return shelf.plan(network, arithmetic)


def cached_plan(network: SpikingNetwork, arithmetic: str = "float64") -> SimPlan:
    """The plan of ``network`` in ``arithmetic``: built on the first call, then reused.

    Raises
    ------
    NetworkError, SimulationError
        As :func:`~backends.reference.plan.build_plan` (nothing is cached then).
    """
    plan = peek_plan(network, arithmetic)
    if plan is not None:
        return plan
    shelf = _shelf(network, create=True)
    with shelf.building:  # threads running frames of one network build its plan once
        plan = peek_plan(network, arithmetic)
        if plan is not None:
            return plan
        parts = _parts(network)
        plan = build_plan(network, arithmetic)  # outside the cache's lock: other networks go on
        with _LOCK:
            if not _same(shelf.parts, parts):
                shelf.clear(parts)
            return shelf.plan(network, arithmetic) or shelf.keep(plan)


def forget_plan(network: SpikingNetwork) -> None:
    """Drop the plans kept for ``network`` (after changing a weight array in place)."""
    shelf = _shelf(network, create=False)
    if shelf is not None:
        with _LOCK:
            shelf.clear()
