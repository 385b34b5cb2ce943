r"""Lowering of the ``classifier`` op: the trained SNN as populations, one step per frame.

Motif ``snn`` (the default). For an input ``(batch..., frame, map0, map1)`` (any order)
and a ``levels`` encoding with one reference level ``L``:

1. **encoder** ``<node>/in`` (source, the value's axes): a latency code with window 1 and
   floor rounding over ``[L, L + 1]`` puts a spike at step 0 exactly where ``x > L``;
2. **input** ``<node>/input`` (axes minus ``frame``, plus ``level`` of size 1 — the first
   layer's input channel): a matrix contracting ``frame`` with weight 1 and **delay f** for
   frame ``f``, into IF neurons with threshold 1 and no memory (``du = dv = 1``), so input
   neuron ``(map0, map1)`` spikes at step ``f`` iff
   ``x[f, map0, map1] > L`` — frame ``f`` arrives at step ``f``;
3. one population ``<node>/l<i>`` per layer of :func:`ir.classifier_forward.layers.build_layer_plan`
   with axes ``(batch..., l<i>_c, l<i>_y, l<i>_x)`` (maps) or ``(batch..., l<i>_n)``, fed by a
   sparse :class:`~compiler.snn.MatrixProjection` of the plan's matrix (the convolutions
   unrolled: a stencil cannot mix channels or stride), shared over the batch axes; a
   recurrent layer adds its ``R`` with delay 1; the parameters are the plan's
   :class:`~compiler.snn.NeuronParams` unchanged;
4. the integrator ``<node>/out`` has axes ``(batch..., class)`` and a ``membrane`` decoder
   read after the last frame: the scores.

So the step simulator computes exactly the sums of :mod:`ir.classifier_forward.forward`
(same matrices, same update order, zero-delay projections within a step).

A ``real`` encoding (graded input currents) and more than one level have no spiking
form here: the rule raises :class:`~ir.errors.CompileError` (use motif ``host``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from compiler.hardware import HardwareProfile
from compiler.lowering.context import LoweringContext
from compiler.lowering.registry import LoweringRegistry
from compiler.lowering.values import SpikeValue, Value
from compiler.snn import Decoder, LatencyCode, NeuronParams, Phase
from ir.classifier_forward.layers import LayerDynamics, LayerPlan, build_layer_plan
from ir.classifier_forward.weights import load_weights
from ir.errors import CompileError
from ir.ops.classify import Classifier

__all__ = ["MOTIF", "lower_classifier", "register_classifier"]

MOTIF = "snn"

#: The input population's channel axis (one entry: the level).
LEVEL_AXIS = "level"

#: The input relays: IF neurons without memory, threshold 1 (a spike in = a spike out).
RELAY = NeuronParams(du=1.0, dv=1.0, v_th=1.0, reset="value")



def neuron_params(dynamics: LayerDynamics) -> NeuronParams:
    """The :class:`~compiler.snn.NeuronParams` of one classifier layer, field for field.

    A read-out (``spiking=False``) keeps its spiking off for the whole frame; a reset or
    reset value left unset takes the neuron model's default.

    Examples
    --------
    >>> neuron_params(LayerDynamics(du=1.0, dv=1.0, v_th=1.0, reset="value")).reset
    'value'
    >>> neuron_params(LayerDynamics(du=0.0, dv=0.0, v_th=1.0, spiking=False)).phases[0].spiking_on
    False
    """
    fields: dict = {"du": dynamics.du, "dv": dynamics.dv, "v_th": dynamics.v_th}
    if dynamics.reset is not None:
        fields["reset"] = dynamics.reset
    if dynamics.v_reset is not None:
        fields["v_reset"] = dynamics.v_reset
    if not dynamics.spiking:
        fields["phases"] = (Phase(start_step=0, spiking_on=False),)
    return NeuronParams(**fields)

def _no_memory(params: NeuronParams, w_min: float, target: HardwareProfile) -> NeuronParams:
    """``dv = 0`` for a memoryless (``dv = 1``) IF neuron on a target without ``dv = 1``,
    where it changes nothing: every weight is at least the threshold and the reset is to 0,
    so after each step the membrane is 0 (no input, or a spike and its reset).

    Examples
    --------
    >>> from compiler.hardware import NO_TARGET, load_profile
    >>> _no_memory(RELAY, 1.0, load_profile("loihi")).dv, _no_memory(RELAY, 0.5, NO_TARGET).dv
    (0.0, 1.0)
    """
    stock = target.full_voltage_decay
    if (stock or params.dv != 1.0 or params.du != 1.0 or params.reset != "value"
            or params.v_reset != 0.0 or w_min < params.v_th or len(params.phases) > 1
            or params.phases[0].bias != 0.0):
        return params
    return params.model_copy(update={"dv": 0.0})


def _check(node: str, op: Classifier) -> float:
    if not op.layers:
        raise CompileError(f"node {node!r} (classifier): an opaque classifier (no layers) "
                           "cannot be lowered; declare its layers or use motif 'host'",
                           node=node)
    enc = op.encoding
    if enc.kind != "levels" or len(enc.levels) != 1:
        what = "a real-valued first layer (graded input currents)" if enc.kind == "real" \
            else f"{len(enc.levels)} levels (one step per frame fits one level)"
        raise CompileError(f"node {node!r} (classifier): encoding {enc.kind!r} with {what} "
                           "has no spiking form; use a 'levels' encoding with one level, or "
                           "motif 'host'", node=node)
    return float(enc.levels[0])


def _axes(plan: LayerPlan, batch: dict[str, int], last: bool) -> dict[str, int]:
    if last:
        return {**batch, "class": plan.shape[0]}
    names = ("c", "y", "x") if len(plan.shape) == 3 else ("n",)
    return {**batch, **{f"l{plan.index}_{a}": n for a, n in zip(names, plan.shape,
                                                                strict=True)}}


def _sparse(m: sp.csr_matrix) -> dict:
    coo = m.tocoo()
    return {"rows": coo.row, "cols": coo.col, "values": coo.data, "n_in_out": coo.shape}


def lower_classifier(ctx: LoweringContext, node: str, op: Classifier,
                     inputs: list[Value]) -> SpikeValue:
    """Lower a classifier node (see the module docstring).

    Raises
    ------
    CompileError
        For an opaque classifier, a ``real`` encoding or several levels.
    IRError
        If the weights file is missing or does not fit the layers.
    """
    level = _check(node, op)
    (value,) = inputs
    t = ctx.types[value.node]
    map_shape = (t.axes[op.map_axes[0]], t.axes[op.map_axes[1]])
    plans = build_layer_plan(op, load_weights(op, map_shape, node), map_shape, node)
    batch = {a: t.axes[a] for a in op.batch_axes(t)}
    frames = t.axes[op.time_axis]
    code = LatencyCode(t_min=0, t_max=1, x_min=level, x_max=level + 1.0, rounding="floor")
    src = ctx.encode(value, consumer=node, code=code, motif=MOTIF)
    b = ctx.builder()
    relay_shape = {**{a: n for a, n in t.axes.items() if a != op.time_axis}, LEVEL_AXIS: 1}
    prev = b.population(node, "input", relay_shape, _no_memory(RELAY, 1.0, ctx.target),
                        motif=MOTIF)
    b.matrix(node, "frames", src.id, prev.id, contract=(op.time_axis,), produce=(LEVEL_AXIS,),
             motif=MOTIF, rows=np.arange(frames), cols=np.zeros(frames, np.int64),
             values=np.ones(frames), n_in_out=(frames, 1), delays=np.arange(frames))
    contract = (LEVEL_AXIS, *op.map_axes)
    for k, plan in enumerate(plans):
        last = k == len(plans) - 1
        axes = _axes(plan, batch, last)
        params = neuron_params(plan.params)
        if plan.matrix.nnz and plan.recurrent is None:
            params = _no_memory(params, float(plan.matrix.data.min()), ctx.target)
        pop = b.population(node, "out" if last else f"l{plan.index}", axes, params,
                           motif=MOTIF)
        produce = tuple(a for a in axes if a not in batch)
        b.matrix(node, f"w{plan.index}", prev.id, pop.id, contract=contract, produce=produce,
                 motif=MOTIF, **_sparse(plan.matrix))
        if plan.recurrent is not None:
            rec = _sparse(plan.recurrent)
            b.matrix(node, f"r{plan.index}", pop.id, pop.id, contract=produce,
                     produce=produce, motif=MOTIF, delays=np.ones(rec["values"].size,
                                                                  np.int64), **rec)
        prev, contract = pop, produce
    b.meta.setdefault("classifier", {})[node] = {
        "frames": frames, "level": level, "layers": [p.kind for p in plans],
        "instances": int(np.prod(list(batch.values()) or [1]))}
    decoder = Decoder(port=node, population=prev.id, kind="membrane", node=node)
    return ctx.spike_value(node, prev, decoder, (0, frames), kind="classifier-membrane")


def register_classifier(registry: LoweringRegistry) -> None:
    """Register the ``snn`` motif of :class:`~ir.ops.classify.Classifier` (the default)."""
    registry.register(Classifier, MOTIF, lower_classifier, default=True)

