"""Plans kept per network: :func:`~backends.reference.simulate` builds each one once.

Building a :class:`~backends.reference.plan.SimPlan` (index maps, stencil edges, factored
weight cores) costs several times what simulating one frame in closed form does, so a
caller that runs a network — or a program, :func:`~backends.reference.run_program` —
frame after frame must not rebuild it per call.  :func:`cached_plan` keeps one plan per
network and arithmetic for as long as the network lives (the cache holds it weakly).

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

import threading
import weakref

from backends.reference.plan import SimPlan, build_plan
from compiler.snn.network import SpikingNetwork

__all__ = ["cached_plan", "forget_plan", "peek_plan"]

_LOCK = threading.Lock()
#: network -> (its parts when the plans were built, {arithmetic: plan})
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: network -> the lock held while its plan is built
_BUILDING: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_PORTS = ("populations", "projections", "encoders", "decoders")


def _parts(net: SpikingNetwork) -> tuple:
    """What a plan depends on: the step count and the part objects themselves."""
    return (net.n_steps, *(tuple(getattr(net, name)) for name in _PORTS))


def _same(a: tuple, b: tuple) -> bool:
    """Whether two :func:`_parts` tuples have equal step counts and the same objects."""
    return a[0] == b[0] and all(
        len(x) == len(y) and all(u is v for u, v in zip(x, y, strict=True))
        for x, y in zip(a[1:], b[1:], strict=True))


def peek_plan(network: SpikingNetwork, arithmetic: str) -> SimPlan | None:
    """The cached plan of ``network`` if there is a current one (never builds one)."""
    with _LOCK:
        held = _CACHE.get(network)
        if held is None or not _same(held[0], _parts(network)):
            return None
        return held[1].get(arithmetic)


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
    with _LOCK:
        building = _BUILDING.setdefault(network, threading.Lock())
    with building:  # threads running frames of one network build its plan once
        plan = peek_plan(network, arithmetic)
        if plan is not None:
            return plan
        parts = _parts(network)
        plan = build_plan(network, arithmetic)  # outside the cache's lock: other networks go on
        with _LOCK:
            held = _CACHE.get(network)
            if held is None or not _same(held[0], parts):
                held = (parts, {})
                _CACHE[network] = held
            return held[1].setdefault(arithmetic, plan)


def forget_plan(network: SpikingNetwork) -> None:
    """Drop the plans kept for ``network`` (after changing a weight array in place)."""
    with _LOCK:
        _CACHE.pop(network, None)
