"""A CFAR code whose top is a calibration quantile below 1 saturates by design.

CA-CFAR's default code tops out at the 99.9 % calibration quantile, and paper 000's Fig.-7
setting puts OS-CFAR's at 99 %: the largest cells of the very maps the chain was calibrated
on lie above the code and are clipped on purpose.  Those encoders are marked ``saturate``, so
the default ``reject`` policy does not refuse the calibration data itself; their clipped
values are still counted.  A code topped at the calibration maximum (OS's default) keeps
refusing values beyond it.
"""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest

from backends.emit import emit_numpy
from backends.reference import run_program
from compiler.compile import compile_graph
from ir import Graph
from ir.errors import SimulationError


def _chain(kind: str) -> Graph:
    return Graph.from_dict({"name": f"{kind}-cfar", "nodes": [
        {"id": "rd", "op": "input", "shape": {"range": 24, "doppler": 8}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "rd", "kind": kind, "axes": ["range", "doppler"],
         "guard": [1, 1], "train": [2, 2], "alpha": 4.0, **({"k": 20} if kind == "os" else {}),
         "edge": ["clip", "wrap"]},
        {"id": "out", "op": "output", "input": "det"}]})


def _maps(seed: int, n: int = 3) -> np.ndarray:
    maps = np.random.default_rng(seed).exponential(1.0, size=(n, 24, 8))
    maps[:, 5, 3] += 60.0  # a target
    return maps


@pytest.mark.parametrize(("kind", "quantiles"), [("ca", None), ("os", (0.01, 0.99))])
def test_a_quantile_topped_code_clips_its_own_calibration_data(kind, quantiles) -> None:
    maps = _maps(0)
    options = {} if quantiles is None else {"cfar_quantiles": {kind: list(quantiles)}}
    program = compile_graph(_chain(kind), None, calibration_inputs={"rd": maps},
                            options=options)
    (encoder,) = program.networks[0].encoders
    assert encoder.saturate
    top = encoder.code.x_max
    assert (maps[0] > top).any()  # the calibration data itself goes above the code's top
    result = run_program(program, {"rd": maps[0]})  # the default policy: reject
    assert result.clipped["rd"] > 0
    assert result.outputs["out"][5, 3]


def test_a_code_topped_at_the_maximum_still_refuses_more() -> None:
    maps = _maps(0)
    program = compile_graph(_chain("os"), None, calibration_inputs={"rd": maps})
    (encoder,) = program.networks[0].encoders
    assert not encoder.saturate
    run_program(program, {"rd": maps[0]})  # within the calibration: fine
    louder = maps[0].copy()
    louder[5, 3] = 10.0 * maps.max()
    with pytest.raises(SimulationError, match="input 'rd': 1 of 192 values are above"):
        run_program(program, {"rd": louder})


def test_an_explicit_cfar_range_is_not_saturating() -> None:
    program = compile_graph(_chain("ca"), None, calibration_inputs={"rd": _maps(0)},
                            options={"cfar_range": (0.01, 8.0)})
    (encoder,) = program.networks[0].encoders
    assert not encoder.saturate
    with pytest.raises(SimulationError, match="input 'rd'"):
        run_program(program, {"rd": _maps(0)[0]})


def test_generated_packages_clip_saturating_codes_too(tmp_path) -> None:
    maps = _maps(0)
    program = compile_graph(_chain("ca"), None, calibration_inputs={"rd": maps})
    ref = run_program(program, {"rd": maps[0]})
    sys.path.insert(0, str(tmp_path))
    try:
        pkg = importlib.import_module(emit_numpy(program, tmp_path, name="sat_pkg").name)
        out = pkg.run({"rd": maps[0]})
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("sat_pkg", None)
    np.testing.assert_array_equal(out["out"], ref.outputs["out"])
