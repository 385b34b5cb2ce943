r"""The resonate-and-fire neuron (:mod:`compiler.snn.resonator`) in Brian2's equation language.

One Brian2 neuron per *compartment* (so synapses, monitors and membranes keep the flat
indices of the reference); each compartment holds its own copy of the resonator's state
``x, y`` and integrates the same folded drive ``dx + i·dy``: every synapse into a
resonator is wired to its four compartments with the weights ``(wx, wy) = w·(±1, 0)`` or
``w·(0, ±1)`` of the compartment it targets (:func:`fan_to_compartments`).  The per-step
abstract code, with ``on = input_on(t)``::

    xt = x + dx
    yt = y + dy
    Cq = C + renorm(t) * (Ce - C)                 # renormalised populations only
    Sq = S + renorm(t) * (Se - S)
    x  = on * rnd(Cq * xt - Sq * yt) + (1 - on) * x
    y  = on * rnd(Sq * xt + Cq * yt) + (1 - on) * y
    v  = on * (px * x + py * y) + (1 - on) * (v + c * bias(t))

with ``rnd(q) = sign(q)·floor(|q|·2^-F + 1/2)`` for ``F = coef_bits > 0`` (plain
products for ``F = 0``), ``(px, py)`` the compartment's projection ``(1, 0)``,
``(−1, 0)``, ``(0, 1)``, ``(0, −1)``, ``renorm(t)`` 1 on the block-end steps of a
renormalised population (other populations use ``C, S`` directly), threshold
``v >= c·v_th and spiking_on(t) > 0.5 and not fired``.  In fixed point every value is a whole number, so Brian2's own
operation order gives the reference's bits; with float coefficients the two agree to
rounding.

Examples
--------
>>> from compiler.snn.resonator import ResonatorParams
>>> code = resonator_code(ResonatorParams(axis="k", cos=(4096.0,), sin=(0.0,), coef_bits=12), 2)
>>> print(code.update.splitlines()[2])
x = input_on(t) * (sign(C * xt - S * yt) * floor(abs(C * xt - S * yt) * 0.000244140625 + 0.5)) + (1 - input_on(t)) * x
"""  # noqa: E501

from __future__ import annotations

import numpy as np

from backends.brian2.equations import NeuronCode
from backends.brian2.synapses import SynapseList
from compiler.snn.resonator import N_COMPARTMENTS, ResonatorParams

__all__ = ["resonator_code", "fan_to_compartments", "compartment_constants", "ON_PRE",
           "SYNAPSE_MODEL"]

_MODEL = ("x : 1\ny : 1\nv : 1\ndx : 1\ndy : 1\nfired : boolean\nI_in : 1\n"
          "C : 1 (constant)\nS : 1 (constant)\npx : 1 (constant)\npy : 1 (constant)\n"
          "c : 1 (constant)")
#: The block-end coefficients of a renormalised population.
_MODEL_END = "\nCe : 1 (constant)\nSe : 1 (constant)"
#: Synapses into a resonator: the drive of the compartment they target, folded.
SYNAPSE_MODEL = "wx : 1 (constant)\nwy : 1 (constant)"
ON_PRE = "dx_post += wx\ndy_post += wy"
_AX = np.array([1.0, -1.0, 0.0, 0.0])
_AY = np.array([0.0, 0.0, 1.0, -1.0])


def _rnd(expr: str, bits: int) -> str:
    if bits == 0:
        return expr
    return f"sign({expr}) * floor(abs({expr}) * {2.0 ** -bits!r} + 0.5)"


def resonator_code(params: ResonatorParams, n_steps: int) -> NeuronCode:
    """The Brian2 code of a resonator population over ``n_steps`` steps."""
    bias, input_on, spiking_on = params.schedule(n_steps)
    f, renorm = params.coef_bits, bool(params.renorm_steps)
    c, s = ("Cq", "Sq") if renorm else ("C", "S")
    update = "\n".join([
        "xt = x + dx", "yt = y + dy",
        *(["Cq = C + renorm(t) * (Ce - C)", "Sq = S + renorm(t) * (Se - S)"] if renorm else []),
        f"x = input_on(t) * ({_rnd(f'{c} * xt - {s} * yt', f)}) + (1 - input_on(t)) * x",
        f"y = input_on(t) * ({_rnd(f'{s} * xt + {c} * yt', f)}) + (1 - input_on(t)) * y",
        "v = input_on(t) * (px * x + py * y) + (1 - input_on(t)) * (v + c * bias(t))",
        "dx = 0", "dy = 0"])
    return NeuronCode(
        model=_MODEL + (_MODEL_END if renorm else ""), update=update,
        threshold="v >= c * v_th and spiking_on(t) > 0.5 and not fired", reset="fired = True",
        constants={"v_th": float(params.v_th)}, bias=bias.astype(np.float64),
        input_on=input_on.astype(np.float64), spiking_on=spiking_on.astype(np.float64),
        timed={"renorm": params.renorm_schedule(n_steps).astype(np.float64)} if renorm else {})


def compartment_constants(params: ResonatorParams, shape: dict[str, int],
                          n_frames: int) -> dict[str, np.ndarray]:
    """``C, S, px, py, c`` (and ``Ce, Se``) per Brian2 neuron (compartment), ``n_frames`` frames."""
    cos, sin = params.per_resonator(shape)
    n_res = cos.size
    scale = params.scale_of(shape)
    ends = {}
    if params.renorm_steps:
        ce, se = params.per_resonator(shape, end=True)
        ends = {"Ce": np.tile(np.repeat(ce, N_COMPARTMENTS), n_frames),
                "Se": np.tile(np.repeat(se, N_COMPARTMENTS), n_frames)}
    return {**ends, "C": np.tile(np.repeat(cos, N_COMPARTMENTS), n_frames),
            "S": np.tile(np.repeat(sin, N_COMPARTMENTS), n_frames),
            "px": np.tile(_AX, n_res * n_frames), "py": np.tile(_AY, n_res * n_frames),
            "c": np.ones(n_res * N_COMPARTMENTS * n_frames) if scale is None
            else np.tile(scale, n_frames)}


def fan_to_compartments(syn: SynapseList) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray, np.ndarray]:
    """``(pre, post, wx, wy, delay)``: each synapse wired to the four compartments of the
    resonator it targets, with the folded weights of its own compartment.

    Examples
    --------
    >>> s = SynapseList(np.array([0]), np.array([5]), np.array([2.0]), np.array([0]))
    >>> [a.tolist() for a in fan_to_compartments(s)[1:4]]
    [[4, 5, 6, 7], [-2.0, -2.0, -2.0, -2.0], [0.0, 0.0, 0.0, 0.0]]
    """
    k = np.arange(N_COMPARTMENTS)
    comp = syn.post % N_COMPARTMENTS
    post = (syn.post - comp)[:, None] + k[None, :]
    def rep(a: np.ndarray) -> np.ndarray:
        return np.repeat(a, N_COMPARTMENTS)

    return (rep(syn.pre), post.ravel(), rep(syn.weight * _AX[comp]),
            rep(syn.weight * _AY[comp]), rep(syn.delay))
