"""Fuzz: every field of every typed motif option model (``compiler/lowering/options.py``) at
hostile and boundary values, on every built-in profile and board, through the motif it
configures.

``compile_graph`` either compiles — and then the program runs to finite outputs — or raises a
:class:`~ir.errors.RadarSNNError` naming the option, the node or the target; never another
exception (a ``ZeroDivisionError`` of a one-bit payload, a pydantic ``ValidationError`` of a
decoder gain of 0, ...).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from fuzz_support import JUNK, budget, outcome
from hypothesis import given, note
from hypothesis import strategies as st

from backends.reference import run_program
from compiler.hardware import BUILTIN_BOARDS, BUILTIN_PROFILES
from compiler.lowering.options import (
    MOTIF_OPTION_MODELS,
    CfarOptions,
    FftOptions,
    RateOptions,
    ResonatorOptions,
    TimeDftOptions,
    TimeInputOptions,
)
from ir import Graph

GRAPH = Graph.from_dict({"name": "opts", "nodes": [
    {"id": "x", "op": "input", "shape": {"sample": 32}},
    {"id": "f", "op": "dft", "input": "x", "axis": "sample", "keep": "positive"},
    {"id": "m", "op": "magnitude", "input": "f"},
    {"id": "c", "op": "cfar", "input": "m", "kind": "ca", "guard": 0, "train": 1, "alpha": 1.5},
    {"id": "o", "op": "output", "input": "c"}]})
X = {"x": np.random.default_rng(0).standard_normal((3, 32))}
#: The ``dft`` motif each model configures (CFAR options act on the CFAR whatever it is).
MOTIF = {TimeDftOptions: "time", TimeInputOptions: "time", FftOptions: "time-fft",
         RateOptions: "rate", ResonatorOptions: "resonator", CfarOptions: "time"}
FIELDS = [(model, name) for model in MOTIF_OPTION_MODELS for name in model.model_fields]
#: Values at and beyond the models' bounds (and the math's: subnormal decays, one bit).
EDGE_VALUES = [
    0, 1, 2, 3, 4, 7, 8, 12, 16, 24, 29, 30, 31, 32, 63, 64, 65, 2**31, -1, 1.0, 1.5, 0.999,
    1e-3, 2.0**-12, 1e-5, 1e-300, 5e-324, 1e300, math.nan, math.inf, True, False, None,
    "auto", "off", "time", "graded", "nearest", "dither", "constant", "companding", "none",
    "weights", "neurons", "static", "per-input", "balanced", "exact", [4, 4], [2], [1],
    [0.0, 1.0], [1.0, 0.0], [0.1, 0.9], {"c": [0.0, 1.0]}, {"ca": [0.2, 0.8]}, {"zz": [0, 1]}]
EDGES = st.sampled_from(EDGE_VALUES)


def _accepted(model, name: str) -> list:
    """The edge values the field's own model accepts (they reach the lowering rules)."""
    out = []
    for value in EDGE_VALUES:
        try:
            model.model_validate({name: value})
        except ValueError:  # pydantic's ValidationError
            continue
        out.append(value)
    return out


#: Per field: an accepted edge value half the time, else an edge or junk value.
SETTINGS = st.sampled_from(FIELDS).flatmap(lambda f: st.tuples(st.just(f), st.one_of(
    st.sampled_from(_accepted(*f) or [None]), st.sampled_from(_accepted(*f) or [None]),
    EDGES, JUNK)))


@budget(0.3)
@given(st.lists(SETTINGS, min_size=1, max_size=3),
       st.sampled_from([*BUILTIN_PROFILES, *BUILTIN_BOARDS]))
def test_every_motif_option_value_compiles_or_is_a_typed_error(settings, target) -> None:
    model = settings[0][0][0]
    options = {name: value for (_, name), value in settings}
    note(f"{target} {MOTIF[model]} {options}")
    culprits = [*options, *map(repr, options.values()), *map(str, options.values()), "'f'",
                "'m'", "'c'", target, "time_steps", "option", "motif", "stage_gains",
                "per_neuron_scales", "graded", "threshold", "weight", "bias", "budget", "cores",
                "steps", "synapse", "neurons", "axons", "memory"]

    def call():
        from compiler.compile import compile_graph

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # drift and out-of-range warnings: reported, fine
            program = compile_graph(GRAPH, target, motifs={"f": MOTIF[model]},
                                    calibration_inputs=X, options=options)
            out = run_program(program, {"x": X["x"][0]}, max_time_s=5.0).outputs["o"]
        assert np.all(np.isfinite(np.asarray(out, dtype=float)))

    outcome(call, culprits)
