"""The explicit state of one lowering run: graph types, options, open networks, segments.

Rules ask the context for what they need instead of reaching for globals:

* :meth:`LoweringContext.builder` — the network currently being built;
* :meth:`LoweringContext.to_host` — make a value available as an array (adds a
  decoder and closes the current spiking segment if the value lives there);
* :meth:`LoweringContext.encode` — a source population carrying a host value
  with a given code (adds an encoder);
* :meth:`LoweringContext.motif_for`, :meth:`LoweringContext.settings_of` (the typed
  options of a motif, :mod:`compiler.lowering.options`),
  :attr:`LoweringContext.calibration` — the choices the user and the calibrate
  pass made.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from compiler.hardware import NO_TARGET, HardwareProfile
from compiler.hardware.neuron_features import check_population
from compiler.lowering.builder import NetworkBuilder
from compiler.lowering.registry import HOST, LoweringRegistry
from compiler.lowering.values import HostValue, SpikeValue, Value
from compiler.memo import CompileMemo
from compiler.program import Segment
from compiler.snn import (
    N_PARTS,
    PART_AXIS,
    Decoder,
    Encoder,
    LatencyCode,
    PartLayout,
    Population,
    RateCode,
)
from ir import Graph
from ir.errors import CompileError
from ir.model import short_repr
from ir.types import TensorType

__all__ = ["LoweringContext", "lower_graph"]

_Model = TypeVar("_Model", bound=BaseModel)


@dataclass
class _Open:
    builder: NetworkBuilder
    closed: bool = False


@dataclass
class LoweringContext:
    """State shared by the lowering rules of one compilation.

    Parameters
    ----------
    graph : ir.Graph
        The (verified) graph being lowered.
    registry : LoweringRegistry
        The rules.
    motifs : mapping of str to str
        The user's motif choices: node id or op name → motif.
    settings : mapping of model class to model
        The motifs' typed options (:func:`compiler.compile.motif_settings`); a
        model not given takes its defaults.
    calibration : dict
        Per-node calibration data from the calibrate pass (node id → record).
    target : HardwareProfile
        The hardware profile, as the compile loaded it (:data:`~compiler.hardware.NO_TARGET`
        for a compile without one): rules read its budgets and number format
        (``ctx.target.number_format``) and nothing else about the chip.
    moving : frozenset of str
        Nodes that compute the moving part of a static split
        (:mod:`compiler.passes.static_split`): the part of the signal that repeats over
        chirps is on the host.
    host_pinned : frozenset of str
        Nodes lowered on the host unless the user chose a motif for that node id (the
        static split's host path and its moving input).
    memo : CompileMemo, optional
        Work shared with the other attempts of a measured compile (:mod:`compiler.memo`);
        None: every result is computed.
    """

    graph: Graph
    registry: LoweringRegistry
    motifs: Mapping[str, str] = field(default_factory=dict)
    settings: Mapping[type[BaseModel], BaseModel] = field(default_factory=dict)
    calibration: dict[str, Any] = field(default_factory=dict)
    target: HardwareProfile = NO_TARGET
    moving: frozenset[str] = frozenset()
    host_pinned: frozenset[str] = frozenset()
    memo: CompileMemo | None = None
    types: dict[str, TensorType] = field(init=False)
    values: dict[str, Value] = field(init=False, default_factory=dict)
    _plan: list[_Open | str] = field(init=False, default_factory=list)

    def __post_init__(self) -> None:
        self.types = self.graph.infer_types()

    def settings_of(self, model: type[_Model]) -> _Model:
        """The typed options of one motif family (its defaults when none were given)."""
        found = self.settings.get(model)
        return found if isinstance(found, model) else model()

    # ------------------------------------------------------------- choices
    def motif_for(self, node: str) -> str:
        """The motif chosen for ``node``: by node id, host if pinned, by op name, the default."""
        op = self.graph.op(node)
        motifs = self.motifs
        if node in motifs:
            motif = motifs[node]
        elif node in self.host_pinned:
            motif = HOST
        else:
            motif = motifs.get(op.op, self.registry.default_motif(type(op)))
        self.registry.rule(type(op), motif, node=node)  # raises a clear error if unknown
        return motif

    # ------------------------------------------------------------ networks
    @property
    def network_index(self) -> int:
        """Index (among spiking segments) of the network :meth:`builder` returns."""
        return self._current()[0]

    def builder(self) -> NetworkBuilder:
        """The open network builder (a new spiking segment after a host segment)."""
        return self._current()[1].builder

    def _current(self) -> tuple[int, _Open]:
        opens = [p for p in self._plan if isinstance(p, _Open)]
        if not opens or opens[-1].closed:
            name = f"{self.graph.name}#{len(opens)}" if opens else self.graph.name
            opens.append(_Open(NetworkBuilder(name)))
            self._plan.append(opens[-1])
        return len(opens) - 1, opens[-1]

    def _opens(self) -> list[_Open]:
        return [p for p in self._plan if isinstance(p, _Open)]

    # ------------------------------------------------------------ boundaries
    def to_host(self, value: Value) -> HostValue:
        """Make ``value`` available on the host (decoding spikes at the end of their segment)."""
        if isinstance(value, HostValue):
            return value
        opened = self._opens()[value.network]
        opened.builder.decoder(value.decoder)
        opened.closed = True
        return HostValue(node=value.node, type=value.type)

    def encode(self, value: Value, *, consumer: str, code: LatencyCode | RateCode,
               split: PartLayout = "none", motif: str,
               normalize_axes: tuple[str, ...] = (), saturate: bool = False) -> Population:
        """A source population in the open network that carries ``value`` with ``code``.

        The population has the value's axes plus a ``part`` axis if ``split``
        adds one; its id is ``"<consumer>/in"`` and its encoder's port is the
        value's node id.  A spike value is decoded to the host first (use its
        spikes directly instead where the consuming motif can).  ``normalize_axes``
        (the ``per-input`` policy) makes the encoder divide each slice over those
        axes by its largest part at run time.  ``saturate`` marks a code whose
        top lies below the calibration maximum on purpose (:class:`Encoder`).
        """
        host = self.to_host(value)
        if not host.type.complex and split in ("re_im", "re_im_signed"):
            raise CompileError(f"node {consumer!r}: split {split!r} needs a complex input, but "
                               f"{host.node!r} is real", node=consumer)
        builder = self.builder()
        if builder.has_encoder(host.node):
            raise CompileError(f"node {consumer!r}: value {host.node!r} is already encoded in "
                               "this network by another consumer; give it one motif",
                               node=consumer)
        shape = dict(host.type.axes)
        if N_PARTS[split]:
            shape[PART_AXIS] = N_PARTS[split]
        pop = builder.population(consumer, "in", shape, motif=motif, source=True)
        builder.encoder(Encoder(port=host.node, population=pop.id, code=code, split=split,
                                node=host.node, normalize_axes=tuple(normalize_axes),
                                saturate=saturate))
        return pop

    def spike_value(self, node: str, population: Population, decoder: Decoder,
                    window: tuple[int, int], **code: Any) -> SpikeValue:
        """Describe ``node``'s value as carried by ``population`` of the open network."""
        if decoder.port != node or decoder.population != population.id:
            decoder = decoder.model_copy(update={"port": node, "population": population.id})
        self.builder().use_steps(window[1])
        return SpikeValue(node=node, type=self.types[node], population=population.id,
                          decoder=decoder, window=window, code=code,
                          network=self.network_index)

    def run_on_host(self, node: str, inputs: list[Value]) -> HostValue:
        """Evaluate ``node`` on the host: decode its inputs, add a host segment."""
        for v in inputs:
            self.to_host(v)
        for opened in self._opens():
            opened.closed = True
        self._plan.append(node)
        return HostValue(node=node, type=self.types[node])

    # ------------------------------------------------------------ result
    def segments(self) -> list[Segment]:
        """The program's segments in execution order (empty networks dropped)."""
        out = []
        for item in self._plan:
            if isinstance(item, str):
                out.append(Segment(kind="host", node=item,
                                   inputs=list(self.graph.inputs_of(item)), outputs=[item]))
            elif not item.builder.is_empty:
                b = item.builder
                out.append(Segment(kind="spiking", network=b.finish(), inputs=b.input_ports,
                                   outputs=b.output_ports))
        return out


def lower_graph(ctx: LoweringContext) -> list[Segment]:
    """Lower every node of ``ctx.graph`` in topological order; return the segments."""
    for node in ctx.graph.topological_order():
        op = ctx.graph.op(node)
        inputs = [ctx.values[i] for i in ctx.graph.inputs_of(node)]
        motif = ctx.motif_for(node)
        rule = ctx.registry.rule(type(op), motif, node=node)
        if rule is None:
            ctx.values[node] = ctx.run_on_host(node, inputs)
        else:
            try:
                ctx.values[node] = rule(ctx, node, op, inputs)
            except ValidationError as err:  # a derived value no code or neuron can hold
                raise CompileError(_invalid_build(ctx, node, motif, err), node=node) from None
            _check_features(ctx, node)
    return ctx.segments()


def _check_features(ctx: LoweringContext, node: str) -> None:
    """Refuse ``node``'s populations where the target's stock neurons lack what they need
    (:mod:`compiler.hardware.neuron_features`)."""
    user = node.split("__")[0]  # the user's node (static-split parts share its id)
    fix = f"use a target whose neurons have it (loihi2) or motifs={{{user!r}: 'host'}}"
    for opened in ctx._opens():
        for pop in opened.builder.populations_of(node):
            check_population(pop, ctx.target, fix=fix)


def _invalid_build(ctx: LoweringContext, node: str, motif: str, err: ValidationError) -> str:
    """The one-line message of a rule whose derived code, neuron or decoder is invalid (an
    option value beyond what the calibrated range allows: ``headroom=1e308`` makes it inf)."""
    given = {k: v for m in ctx.settings.values()
             for k, v in m.model_dump(exclude_defaults=True).items()}
    shown = ", ".join(f"{k}={short_repr(v)}" for k, v in sorted(given.items())) or "none"
    first = err.errors(include_url=False)[0]["msg"]
    return (f"node {node!r} (motif {motif}): the lowering built an invalid {err.title} "
            f"({first}); compile options set: {shown}; give values the calibrated range "
            "can hold (e.g. a smaller headroom or input_range) or another motif")

