"""Compiler records built with a bad value raise typed radarsnn errors (issue 32, item 5).

Each error is both the radarsnn class (``NetworkError`` for the spiking-network records,
``CompileError`` for the compiler's option records) and a pydantic ``ValidationError``,
so code catching either keeps working; the message names the record, the field, the rule
and the value given.
"""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from compiler.accuracy.contract import Tolerances
from compiler.hardware.figures import EnergyFigures, Figure
from compiler.passes.static_split import StaticSplitOptions
from compiler.snn import (
    Decoder,
    Encoder,
    LatencyCode,
    NeuronParams,
    Phase,
    Population,
    RateCode,
)
from compiler.snn.resonator import ResonatorParams
from compiler.snn.stream import StreamCode
from ir.errors import (
    CompileError,
    CompileValidationError,
    NetworkError,
    NetworkValidationError,
    RadarSNNError,
)


def _code() -> LatencyCode:
    return LatencyCode(t_max=8, x_min=0.0, x_max=1.0)


NETWORK_CASES = [
    (lambda: NeuronParams(v_th=-1.0),
     "NeuronParams: field 'v_th': v_th must be a positive finite number, got -1.0 (got -1.0)"),
    (lambda: NeuronParams(du=2.0),
     "NeuronParams: field 'du': Input should be less than or equal to 1 (got 2.0)"),
    (lambda: NeuronParams(reset="never"),
     "NeuronParams: field 'reset': Input should be 'value', 'subtract' or 'fire_once' "
     "(got 'never')"),
    (lambda: NeuronParams(phases=({"start_step": -3},)),
     "NeuronParams: field 'phases.0.start_step': Input should be greater than or equal to 0 "
     "(got -3)"),
    (lambda: NeuronParams(vth=1.0),
     "NeuronParams: field 'vth': Extra inputs are not permitted (got 1.0)"),
    (lambda: Phase(start_step=0, bias=float("inf")),
     "Phase: field 'bias': bias must be finite, got inf (got inf)"),
    (lambda: Population(id="p", shape={"r": 0}),
     "Population: field 'shape': axis sizes must be positive, got {'r': 0} (got {'r': 0})"),
    (lambda: Population(id="", shape={"r": 2}),
     "Population: field 'id': String should have at least 1 character (got '')"),
    (lambda: LatencyCode(t_max=-1, x_min=0.0, x_max=1.0),
     "LatencyCode: field 't_max': Input should be greater than 0 (got -1)"),
    (lambda: StreamCode(axis="r", length=4, inner=2, bits=31, x_max=1.0),
     "StreamCode: field 'bits': Input should be less than or equal to 30 (got 31)"),
    (lambda: Encoder(port="x", population="in", code=_code(), split="sideways"),
     "Encoder: field 'split': "),
    (lambda: Decoder(port="y", population="p", kind="loudness"),
     "Decoder: field 'kind': "),
]


@pytest.mark.parametrize(("build", "message"), NETWORK_CASES)
def test_network_records_raise_network_errors(build, message):
    with pytest.raises(NetworkValidationError) as info:
        build()
    err = info.value
    assert isinstance(err, NetworkError) and isinstance(err, RadarSNNError)
    assert isinstance(err, ValidationError)  # callers that catch pydantic's error still do
    assert str(err).startswith(message)
    assert "\n" not in str(err)  # one line, not pydantic's report


def test_the_error_keeps_pydantic_s_details():
    with pytest.raises(ValidationError) as info:
        NeuronParams(v_th=0.0, du=-1.0)
    err = info.value
    assert err.title == "NeuronParams"
    assert [e["loc"] for e in err.errors()] == [("du",), ("v_th",)]
    assert str(err) == ("NeuronParams: field 'du': Input should be greater than or equal to 0 "
                        "(got -1.0); field 'v_th': v_th must be a positive finite number, "
                        "got 0.0 (got 0.0)")


def test_a_nested_record_names_its_path():
    with pytest.raises(NetworkError, match=r"^Population: field 'params.v_th': v_th must be "
                                           r"a positive finite number, got 0.0"):
        Population(id="p", shape={"r": 2}, params={"v_th": 0.0})


def test_model_validate_raises_the_same_class():
    with pytest.raises(NetworkValidationError, match=r"^NeuronParams: field 'du'"):
        NeuronParams.model_validate({"du": 1.5})
    with pytest.raises(NetworkValidationError, match=r"^RateCode: "):
        RateCode.model_validate({"x_max": "big"})


def test_resonator_params_refusals_are_network_errors():
    with pytest.raises(NetworkError, match="ResonatorParams: "):
        ResonatorParams(axis="r", cos=(1.0,), sin=(0.0, 0.0))


@pytest.mark.parametrize(("build", "message"), [
    (lambda: Tolerances(lost_max=2.0),
     "Tolerances: field 'lost_max': Input should be less than or equal to 1 (got 2.0)"),
    (lambda: StaticSplitOptions(static_split="on"),
     "StaticSplitOptions: field 'static_split': Input should be 'auto' or 'off' (got 'on')"),
    (lambda: Figure(value=-1.0, source="datasheet"),
     "Figure: field 'value': Input should be greater than or equal to 0 (got -1.0)"),
    (lambda: EnergyFigures(spike_j={"value": 1e-12, "source": ""}),
     "EnergyFigures: field 'spike_j.source': String should have at least 1 character (got '')"),
])
def test_compiler_option_records_raise_compile_errors(build, message):
    with pytest.raises(CompileValidationError) as info:
        build()
    assert isinstance(info.value, CompileError) and isinstance(info.value, ValidationError)
    assert str(info.value) == message


def test_good_records_still_build():
    assert NeuronParams(v_th=2.0).v_th == 2.0
    assert Population(id="p", shape={"r": 2}).size == 2
    assert Tolerances().lost_max == 0.01


def test_the_error_pickles_with_its_message():
    import pickle

    with pytest.raises(NetworkValidationError) as info:
        NeuronParams(v_th=-1.0)
    back = pickle.loads(pickle.dumps(info.value))
    assert type(back) is NetworkValidationError and str(back) == str(info.value)
    assert back.errors(include_url=False)[0]["loc"] == ("v_th",)


def test_a_validator_s_own_error_type_keeps_its_text():
    from pydantic import field_validator
    from pydantic_core import PydanticCustomError

    from ir.model import CheckedModel

    class Gain(CheckedModel):
        error_class = CompileValidationError
        db: float

        @field_validator("db")
        @classmethod
        def _audible(cls, value: float) -> float:
            if value > 60:
                raise PydanticCustomError("too_loud", "{db} dB is over 60 dB", {"db": value})
            return value

    with pytest.raises(CompileValidationError) as info:
        Gain(db=70.0)
    assert str(info.value) == "Gain: field 'db': 70.0 dB is over 60 dB (got 70.0)"
    assert info.value.errors(include_url=False)[0]["type"] == "too_loud"


def test_a_hardware_profile_built_with_a_bad_value_raises_a_typed_error():
    from compiler.hardware import load_profile
    from compiler.hardware.profile import HardwareProfile
    from ir.errors import CompileError, CompileValidationError

    with pytest.raises(CompileError, match=r"HardwareProfile: field 'neurons_per_core'.*'many'"):
        HardwareProfile(name="x", neurons_per_core="many")
    with pytest.raises(CompileValidationError, match=r"state_bits.*greater than or equal"):
        load_profile("loihi").model_copy(update={"state_bits": -3})
    with pytest.raises(CompileValidationError, match=r"field '1'"):  # a YAML key 1: 1
        HardwareProfile.model_validate({"name": "x", 1: 1})
