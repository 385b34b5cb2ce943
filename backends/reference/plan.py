"""The simulation plan: everything about a network that does not depend on the inputs.

:func:`build_plan` validates the network once, resolves every population's
schedule into :class:`~backends.reference.neuron.StepParams`, and builds one
delivery per projection (index maps and weight operands, see
:mod:`backends.reference.delivery`).  Both engines read the same plan, and a
plan can be reused across calls of :func:`~backends.reference.simulate`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import networkx as nx
import numpy as np

from backends.reference.delivery import DELIVERY_BUILDERS, Delivery
from backends.reference.gate import GateInputs, gate_inputs
from backends.reference.neuron import StepParams
from backends.reference.resonator import ResonatorStepParams
from backends.reference.run_options import ARITHMETICS  # one source (re-exported here)
from compiler.snn.network import Population, SpikingNetwork
from compiler.snn.resonator import ResonatorParams
from ir.errors import SimulationError

__all__ = ["SimPlan", "build_plan", "closed_form_problems", "ARITHMETICS"]



@dataclass(frozen=True, eq=False)
class SimPlan:
    """A network prepared for simulation.

    Attributes
    ----------
    network : SpikingNetwork
        The (validated) network.
    arithmetic : {"float64", "int64"}
        Number type of currents and membranes.
    order : tuple of str
        Population ids in the per-step evaluation order (zero-delay edges forward).
    neurons : dict
        :class:`StepParams` of every non-source population.
    deliveries : dict
        One delivery per projection id.
    incoming : dict
        Per population, the ids of its incoming projections in declaration order.
    history : dict
        Per population, how many past steps of its spikes a projection reads
        (largest outgoing delay + 1): the length of its ring buffer.
    """

    network: SpikingNetwork
    arithmetic: str
    order: tuple[str, ...]
    neurons: Mapping[str, StepParams]
    deliveries: Mapping[str, Delivery]
    incoming: Mapping[str, tuple[str, ...]]
    history: Mapping[str, int]
    #: Why the closed form cannot run the network (:func:`closed_form_problems`; empty: it can).
    closed_problems: tuple[str, ...] = ()
    #: Fire-once IF populations whose inputs are gated (:mod:`backends.reference.gate`).
    gates: Mapping[str, GateInputs] = field(default_factory=dict)

    @property
    def integer(self) -> bool:
        """Whether the plan uses integer (fixed-point) arithmetic."""
        return self.arithmetic == "int64"

    @property
    def state_limit(self) -> int | None:
        """The chip's state range ``2^(state_bits−1) − 1`` in state units, for a network
        quantized for a target with ``state_bits`` (else ``None``)."""
        meta = self.network.meta if isinstance(self.network.meta, Mapping) else {}
        bits = meta.get("state_bits")  # a forged artifact's value is no limit, never an error
        if isinstance(bits, bool) or not isinstance(bits, int) or not 2 <= bits <= 64:
            return None
        return (1 << (bits - 1)) - 1

    @property
    def populations(self) -> Mapping[str, Population]:
        """Populations by id."""
        return self.network.population

    @property
    def weight_nbytes(self) -> int:
        """Bytes of all weight operands the plan holds (one copy per projection and delay)."""
        return sum(d.weight_nbytes for d in self.deliveries.values())


def build_plan(
    network: SpikingNetwork,
    arithmetic: str = "float64",
    builders: Mapping[type, Callable[..., Delivery]] = DELIVERY_BUILDERS,
) -> SimPlan:
    """Validate ``network`` and precompute what simulating it needs.

    Parameters
    ----------
    network : SpikingNetwork
        The network to simulate.
    arithmetic : {"float64", "int64"}
        ``int64`` requires whole-number weights, thresholds, resets and biases
        and decays that are multiples of ``1/4096``.
    builders : mapping
        Delivery builder per projection type (default :data:`DELIVERY_BUILDERS`).

    Returns
    -------
    SimPlan

    Raises
    ------
    NetworkError
        If the network does not validate.
    SimulationError
        For an unknown arithmetic or projection kind, or parameters that are not
        integers under ``int64`` (naming the population or projection).

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import (Encoder, LatencyCode, MatrixProjection, Population,
    ...                           SpikingNetwork)
    >>> net = SpikingNetwork(name="n", n_steps=4,
    ...     populations=[Population(id="a", shape={"i": 2}, source=True),
    ...                  Population(id="b", shape={"o": 1})],
    ...     projections=[MatrixProjection(id="w", source="a", target="b", contract=("i",),
    ...                                   produce=("o",), weights=np.ones((2, 1)))],
    ...     encoders=[Encoder(port="x", population="a",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))])
    >>> plan = build_plan(net)
    >>> plan.order, plan.incoming["b"], plan.weight_nbytes
    (('a', 'b'), ('w',), 16)
    """
    if arithmetic not in ARITHMETICS:
        raise SimulationError(f"network {network.name!r}: arithmetic {arithmetic!r} is not one of "
                              f"{ARITHMETICS}")
    network.validate()
    integer = arithmetic == "int64"
    pops = network.population
    for proj in network.projections:
        if type(proj) not in builders:
            raise SimulationError(f"projection {proj.id!r}: no delivery for kind {proj.kind!r}; "
                                  f"known kinds: {_kinds(builders)}", node=proj.id)
    if integer:
        _check_integer(network)
    neurons = {p.id: (ResonatorStepParams.of if isinstance(p.params, ResonatorParams)
                      else StepParams.from_params)(p.params, network.n_steps, integer, p.shape)
               for p in network.populations if not p.source}
    deliveries = {q.id: builders[type(q)](q, pops[q.source], pops[q.target], integer)
                  for q in network.projections}
    if not all(p.params.reset == "fire_once" for p in network.populations if not p.source):
        # no closed form for this network: dense steps may use BLAS (rate codes)
        deliveries = {k: replace(d, blas_events=True) if hasattr(d, "blas_events") else d
                      for k, d in deliveries.items()}
    history = {p.id: 1 for p in network.populations}
    for d in deliveries.values():
        history[d.source] = max(history[d.source], max(d.delays) + 1)
    incoming = {p.id: tuple(q.id for q in network.incoming(p.id)) for p in network.populations}
    return SimPlan(
        network=network,
        arithmetic=arithmetic,
        order=tuple(network.population_order()),
        neurons=neurons,
        deliveries=deliveries,
        incoming=incoming,
        history=history,
        closed_problems=tuple(closed_form_problems(network)),
        gates={pid: gates for pid, params in neurons.items()
               if params.reset == "fire_once" and params.du == 1.0 and params.dv == 0.0
               and (gates := gate_inputs(deliveries, incoming[pid])) is not None},
    )


def closed_form_problems(network: SpikingNetwork) -> list[str]:
    """Why the closed form cannot simulate ``network`` (empty when it can).

    Examples
    --------
    >>> import numpy as np
    >>> from compiler.snn import NeuronParams, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4, populations=[
    ...     Population(id="a", shape={"i": 1}, params=NeuronParams(reset="subtract"))])
    >>> closed_form_problems(net)
    ["population 'a' has reset='subtract'; the closed form needs reset='fire_once'"]
    """
    problems = [f"population {p.id!r} has reset={p.params.reset!r}; the closed form needs "
                "reset='fire_once'"
                for p in network.populations if not p.source and p.params.reset != "fire_once"]
    g = nx.DiGraph([(p.source, p.target) for p in network.projections])
    if not nx.is_directed_acyclic_graph(g):
        edges = set(nx.find_cycle(g))
        on_cycle = [p.id for p in network.projections if (p.source, p.target) in edges]
        problems.append(f"projections {on_cycle} form a cycle through populations "
                        f"{[u for u, _ in edges]}; the closed form needs an acyclic "
                        "population graph")
    return problems


def _kinds(builders: Mapping[type, Callable[..., Delivery]]) -> list[str]:
    """The ``kind`` tags of the projection types in ``builders``, sorted (for messages)."""
    return sorted(getattr(t, "kind", t.__name__) for t in builders)


def _check_integer(network: SpikingNetwork) -> None:
    fix = "quantize the network first (integer weights, thresholds, biases; decays k/4096)"
    for pop in network.populations:
        if not pop.source and not pop.params.is_integer():
            p = pop.params
            raise SimulationError(
                f"population {pop.id!r}: arithmetic='int64' needs whole-number v_th, v_reset and "
                f"biases and decays that are multiples of 1/4096; got v_th={p.v_th}, "
                f"v_reset={p.v_reset}, biases={[ph.bias for ph in p.phases]}, du={p.du}, "
                f"dv={p.dv}; {fix}", node=pop.id)
    for proj in network.projections:
        w = np.asarray(proj.stored_weights())
        bad = w != np.rint(w)
        if bad.any():
            raise SimulationError(
                f"projection {proj.id!r}: arithmetic='int64' needs whole-number weights; "
                f"{int(bad.sum())} of {w.size} are not (e.g. {float(w[bad][0])}); {fix}",
                node=proj.id)
