"""One source for the run modes and arithmetics (backends.reference.run_options).

The engines of ``simulate``, the modes ``RunOptions.checked`` accepts, the plan's arithmetics,
the command line's ``--mode`` choices and the sweep spec's ``mode`` are the same lists; the
CLI and the sweep spec spell them out (they are read before numpy is imported), so this test
keeps them equal.
"""

from __future__ import annotations

import typing

import numpy as np
import pytest

from backends.reference import RunOptions, plan, simulate
from backends.reference.run_options import ARITHMETICS, ENGINE_MODES, MODES
from backends.reference.simulate import ENGINES
from ir.errors import SimulationError
from radarsnn.cli import build_parser
from radarsnn.sweep.spec import SweepSpec


def _choices(command: str, flag: str) -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return list(next(a for a in sub._actions if flag in a.option_strings).choices)


def test_every_list_of_modes_is_the_one_in_run_options():
    assert tuple(ENGINES) == ENGINE_MODES and MODES == (*ENGINE_MODES, "auto")
    assert plan.ARITHMETICS is ARITHMETICS
    assert tuple(_choices("run", "--mode")) == MODES
    assert sorted(_choices("bench", "--mode")) == sorted(ENGINE_MODES)
    assert typing.get_args(SweepSpec.model_fields["mode"].annotation) == MODES


def _tiny():
    from compiler.snn import LatencyCode, NeuronParams
    from compiler.snn.examples import tiny_network

    return tiny_network(n_steps=6, params=NeuronParams(du=0.0, v_th=3.0, reset="fire_once"),
                        code=LatencyCode(t_max=4, x_min=0.0, x_max=1.0))


@pytest.mark.parametrize("options, message", [
    (RunOptions(mode="fast"), r"network 'tiny': mode 'fast' is not one of \('step', 'closed', "
                              r"'auto'\)"),
    (RunOptions(arithmetic="int32"), r"network 'tiny': arithmetic 'int32' is not one of "
                                     r"\('float64', 'int64'\)"),
    (RunOptions(workers=0), r"network 'tiny': workers=0 must be a whole number >= 1"),
    (RunOptions(max_time_s=-1.0), r"max_time_s")])
def test_simulate_checks_its_options_with_run_options_checked(options, message):
    with pytest.raises(SimulationError, match=message):
        simulate(_tiny(), {"x": np.array([1.0, 0.5])}, options=options)
