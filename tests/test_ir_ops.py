"""Each op: hand-worked output types, and every verify rule raising IRError naming the node."""

from __future__ import annotations

import re

import pytest

from ir import (
    CFAR,
    DFT,
    OP_REGISTRY,
    AdcInput,
    ChainFileError,
    Classifier,
    Graph,
    Input,
    IRError,
    Linear,
    Log,
    Magnitude,
    Output,
    Sum,
    TensorType,
    Threshold,
    Window,
)

CUBE = TensorType(axes={"rx": 4, "chirp": 64, "sample": 256}, complex=True)
RD = TensorType(axes={"doppler": 64, "range": 256}, domain="power")


def _chain(*nodes: dict) -> dict:
    """A chain dict of ``nodes`` followed by an output reading the last one."""
    return {"name": "t", "nodes": [*nodes, {"id": "out", "op": "output", "input": nodes[-1]["id"]}]}


def _src(shape: dict, **kw: object) -> dict:
    return {"id": "src", "op": "input", "shape": shape, **kw}


def _fails(data: dict, node: str, match: str, cls: type[IRError] = IRError) -> IRError:
    """Building and verifying ``data`` raises ``cls`` about ``node`` matching ``match``."""
    with pytest.raises(cls, match=match) as info:
        Graph.from_dict(data).verify()
    assert info.value.node == node
    assert f"'{node}'" in str(info.value)
    return info.value


# -- hand-worked output types ---------------------------------------------------------------


def test_io_types() -> None:
    adc = AdcInput(shape={"chirp": 2, "sample": 8}, complex=True)
    assert adc.infer("adc", []) == TensorType(axes={"chirp": 2, "sample": 8}, complex=True)
    assert AdcInput(shape={"s": 3}).infer("a", []).complex is False
    assert Input(shape={"range": 4}, domain="mask").infer("m", []).domain == "mask"
    assert Output().infer("out", [RD]) == RD


def test_window_and_dft_types() -> None:
    assert Window(axis="sample", kind="blackman").infer("w", [CUBE]) == CUBE
    real = CUBE.replace(complex=False)
    rng = DFT(axis="sample", out_axis="range", keep="positive").infer("r", [real])
    assert rng == TensorType(axes={"rx": 4, "chirp": 64, "range": 128}, complex=True)
    dop = DFT(axis="chirp", out_axis="doppler", shift=True, n_fft=100).infer("d", [rng])
    assert dop.axes == {"rx": 4, "doppler": 100, "range": 128}
    # n_fft = 9 with keep positive: bins 0..3 (floor(9/2) = 4)
    assert DFT(axis="sample", n_fft=9, keep="positive").infer("d", [
        TensorType(axes={"sample": 8})]).axes == {"sample": 4}


def test_linear_and_sum_types() -> None:
    t = TensorType(axes={"rx": 2, "range": 5})
    real = Linear(axis="rx", out_axis="beam", matrix=[[1, 1], [1, -1], [0, 2]]).infer("l", [t])
    assert real == TensorType(axes={"beam": 3, "range": 5})
    cplx = Linear(axis="rx", matrix=[[1, 0]], matrix_imag=[[0, 1]]).infer("l", [t])
    assert cplx == TensorType(axes={"rx": 1, "range": 5}, complex=True)
    assert Sum(axis="rx").infer("s", [CUBE]) == TensorType(
        axes={"chirp": 64, "sample": 256}, complex=True)
    assert Sum(axis="doppler").infer("s", [RD]) == TensorType(axes={"range": 256}, domain="power")


@pytest.mark.parametrize(("kind", "domain"), [("l2", "amplitude"), ("l1", "amplitude"),
                                              ("square", "power")])
def test_magnitude_types(kind: str, domain: str) -> None:
    out = Magnitude(kind=kind).infer("m", [CUBE])
    assert out == TensorType(axes=CUBE.axes, complex=False, domain=domain)
    assert Magnitude(kind=kind).infer("m", [CUBE.replace(complex=False)]).domain == domain


def test_log_threshold_cfar_classifier_types() -> None:
    assert Log().infer("l", [RD]) == RD.replace(domain="db")
    assert Threshold(value=3.0).infer("t", [RD]) == RD.replace(domain="mask")
    det = CFAR(kind="ca", guard=1, train=2, pfa=1e-3).infer("c", [RD])
    assert det == RD.replace(domain="mask")
    assert Classifier(num_classes=3, weights="w.npz").infer("k", [RD]) == TensorType(
        axes={"class": 3})


def test_cfar_window_resolution_hand_worked() -> None:
    # The paper's 15 x 15 window with a 7 x 7 guard block: 225 - 49 = 176 training cells.
    op = CFAR(kind="os", guard=[3, 3], train=[4, 4], k=132, alpha=1.2, edge=["clip", "wrap"])
    win = op.window("det", RD)
    assert (win.axes, win.sizes, win.n_train) == (("doppler", "range"), (15, 15), 176)
    assert win.edge == ("clip", "wrap")
    # 1D: 2 guard + 8 train per side -> 2 * 8 = 16 cells; axes chosen and broadcast
    one = CFAR(kind="ca", axes=["range"], guard=2, train=8, alpha=3.0).window("c", RD)
    assert (one.axes, one.guard, one.train, one.edge, one.n_train) == (
        ("range",), (2,), (8,), ("clip",), 16)
    # train 0 on one axis: window 3 x 1 minus guard 1 x 1 = 2 cells
    assert CFAR(kind="ca", guard=[0, 0], train=[1, 0], alpha=1.0).window("c", RD).n_train == 2


def test_every_registered_op_has_a_math_docstring_and_snake_name() -> None:
    for name, cls in OP_REGISTRY.items():
        assert re.fullmatch(r"[a-z]+(_[a-z]+)*", name)
        assert cls.op_name() == name
        assert cls.__doc__ and "Examples" in cls.__doc__


# -- verify rules: each raises IRError naming the node --------------------------------------

SIG = {"shape": {"chirp": 8, "sample": 16}}


def test_unknown_axis_names_the_available_axes() -> None:
    for op in ({"op": "window"}, {"op": "dft"}, {"op": "sum"},
               {"op": "linear", "matrix": [[1.0] * 16]}):
        err = _fails(_chain(_src(**SIG), {"id": "n1", "input": "src", "axis": "smple", **op}),
                     "n1", "axis 'smple' is not an axis of the input")
        assert "available axes: ('chirp', 'sample')" in str(err)
    _fails(_chain(_src(**SIG), {"id": "det", "op": "cfar", "input": "src", "kind": "ca",
                                "axes": ["range"], "guard": 0, "train": 1, "alpha": 2.0}),
           "det", r"axes entry 'range' is not an axis of the input; available axes")


def test_duplicate_axis_names_are_rejected() -> None:
    _fails(_chain(_src(**SIG), {"id": "rng", "op": "dft", "input": "src", "axis": "sample",
                                "out_axis": "chirp"}),
           "rng", "out_axis 'chirp' duplicates an existing axis name")
    _fails(_chain(_src(**SIG), {"id": "lin", "op": "linear", "input": "src", "axis": "chirp",
                                "out_axis": "sample", "matrix": [[1.0] * 8]}),
           "lin", "out_axis 'sample' duplicates an existing axis name")
    _fails(_chain(_src(**SIG), {"id": "det", "op": "cfar", "input": "src", "kind": "ca",
                                "axes": ["sample", "sample"], "guard": 0, "train": 1,
                                "alpha": 2.0}),
           "det", "repeat an axis name")


@pytest.mark.parametrize(
    ("node", "match"),
    [
        ({"op": "adc_input", "shape": {"a": 0}}, r"field 'shape\.a': Input should be greater"),
        ({"op": "adc_input", "shape": {"a": -2}}, r"field 'shape\.a'"),
        ({"op": "input", "shape": {}}, r"field 'shape'.*at least 1 item"),
        ({"op": "input", "shape": {"a": 2}, "complex": True, "domain": "mask"},
         "only 'amplitude' may be complex"),
    ],
)
def test_sizes_and_shapes_are_checked_at_load(node: dict, match: str) -> None:
    data = {"nodes": [{"id": "src", **node}, {"id": "out", "op": "output", "input": "src"}]}
    _fails(data, "src", match, ChainFileError)


def test_wrong_number_of_inputs() -> None:
    _fails({"nodes": [_src({"a": 4}), {"id": "b", "op": "input", "shape": {"a": 4}},
                      {"id": "win", "op": "window", "inputs": ["src", "b"], "axis": "a"},
                      {"id": "out", "op": "output", "input": "win"}]},
           "win", r"takes 1 input, got 2")
    _fails({"nodes": [_src({"a": 4}), {"id": "b", "op": "input", "shape": {"a": 4}, "input": "src"},
                      {"id": "out", "op": "output", "input": "b"}]},
           "b", r"takes 0 inputs, got 1")
    _fails({"nodes": [_src({"a": 4}), {"id": "mag", "op": "magnitude", "inputs": []},
                      {"id": "out", "op": "output", "inputs": ["src", "mag"]}]},
           "mag", r"takes 1 input, got 0")


def test_dft_rules() -> None:
    _fails(_chain(_src(**SIG), {"id": "rng", "op": "dft", "input": "src", "axis": "sample",
                                "n_fft": 8}),
           "rng", r"n_fft=8 is smaller than axis 'sample' of size 16; use n_fft >= 16")
    _fails(_chain(_src({"s": 1}), {"id": "rng", "op": "dft", "input": "src", "axis": "s",
                                   "keep": "positive"}),
           "rng", "keep='positive' needs n_fft >= 2")
    _fails(_chain(_src(**SIG), {"id": "rng", "op": "dft", "input": "src", "axis": "sample",
                                "n_fft": 0}),
           "rng", r"field 'n_fft': Input should be greater than 0", ChainFileError)


def test_linear_rules() -> None:
    _fails(_chain(_src(**SIG), {"id": "bf", "op": "linear", "input": "src", "axis": "chirp",
                                "matrix": [[1.0, 2.0, 3.0]]}),
           "bf", r"matrix has 3 columns but axis 'chirp' has size 8")
    _fails(_chain(_src(**SIG), {"id": "bf", "op": "linear", "input": "src", "axis": "chirp",
                                "matrix": [[1.0, 2.0], [3.0]]}),
           "bf", r"rows must all have the same length", ChainFileError)
    _fails(_chain(_src(**SIG), {"id": "bf", "op": "linear", "input": "src", "axis": "chirp",
                                "matrix": [[1.0, 2.0]], "matrix_imag": [[1.0]]}),
           "bf", r"matrix_imag must have the shape of matrix \(1 x 2\)", ChainFileError)
    with pytest.raises(IRError, match=r"op 'linear': field 'matrix\.0\.0': .*finite"):
        Linear(axis="a", matrix=[[float("inf")]])


def test_sum_rules() -> None:
    _fails(_chain(_src({"range": 4}), {"id": "s", "op": "sum", "input": "src", "axis": "range"}),
           "s", "it is the only axis")
    _fails(_chain(_src({"a": 2, "b": 2}, domain="db"),
                  {"id": "s", "op": "sum", "input": "src", "axis": "a"}),
           "s", r"input domain 'db' is not accepted; sum takes \['amplitude', 'power'\]")


@pytest.mark.parametrize("op", ["log", "threshold", "cfar", "classifier"])
def test_complex_input_is_rejected(op: str) -> None:
    params = {"log": {}, "threshold": {"value": 1.0},
              "cfar": {"kind": "ca", "guard": 0, "train": 1, "alpha": 2.0},
              "classifier": {"num_classes": 2, "weights": "w"}}[op]
    _fails(_chain(_src(**SIG, complex=True), {"id": "n1", "op": op, "input": "src", **params}),
           "n1", f"input is complex; {op} takes real values")


@pytest.mark.parametrize(
    ("op", "domain"),
    [("window", "power"), ("dft", "mask"), ("magnitude", "power"), ("log", "db"),
     ("log", "mask"), ("threshold", "mask"), ("cfar", "mask"), ("classifier", "mask")],
)
def test_domains_are_checked(op: str, domain: str) -> None:
    params = {"window": {"axis": "sample"}, "dft": {"axis": "sample"}, "magnitude": {}, "log": {},
              "threshold": {"value": 1.0},
              "cfar": {"kind": "ca", "guard": 0, "train": 1, "alpha": 2.0},
              "classifier": {"num_classes": 2, "weights": "w"}}[op]
    _fails(_chain(_src(**SIG, domain=domain), {"id": "n1", "op": op, "input": "src", **params}),
           "n1", f"input domain '{domain}' is not accepted")


CFAR_OK = {"id": "det", "op": "cfar", "input": "src", "kind": "os", "guard": [3, 3],
           "train": [4, 4], "k": 132, "alpha": 1.2}
RD_SRC = _src({"doppler": 64, "range": 256}, domain="power")


def test_cfar_reference_chain_verifies() -> None:
    Graph.from_dict(_chain(RD_SRC, CFAR_OK)).verify()


@pytest.mark.parametrize(
    ("change", "match", "cls"),
    [
        ({"k": 177}, r"k=177 is outside 1\.\.176 \(N_train for guard \[3, 3\], train \[4, 4\]\)",
         IRError),
        ({"k": 0}, r"field 'k': Input should be greater than 0", ChainFileError),
        ({"k": None}, "kind 'os' needs the rank 'k'", ChainFileError),
        ({"kind": "ca"}, "'k' is only for kind 'os'", ChainFileError),
        ({"alpha": 0.0}, r"field 'alpha': Input should be greater than 0", ChainFileError),
        ({"alpha": -1.5}, r"field 'alpha'", ChainFileError),
        ({"alpha": None, "pfa": 0.0}, r"field 'pfa': Input should be greater than 0",
         ChainFileError),
        ({"alpha": None, "pfa": 1.0}, r"field 'pfa': Input should be less than 1",
         ChainFileError),
        ({"pfa": 1e-3}, "exactly one of 'alpha' and 'pfa'", ChainFileError),
        ({"alpha": None}, "exactly one of 'alpha' and 'pfa'", ChainFileError),
        ({"guard": [3, 3, 3]}, r"guard has 3 entries but the CFAR spans 2 axes", IRError),
        ({"edge": ["wrap"]}, r"edge has 1 entries but the CFAR spans 2 axes", IRError),
        ({"edge": "mirror"}, r"field 'edge': Input should be 'wrap' or 'clip'", ChainFileError),
        ({"guard": -1}, r"field 'guard': Input should be greater than or equal to 0",
         ChainFileError),
        ({"train": [0, 0], "k": 1}, r"no training cells \(train=\[0, 0\]\)", IRError),
        ({"train": [4, 200]},
         r"window 2\*\(guard\+train\)\+1 = 2\*\(3\+200\)\+1 = 407 is larger than axis 'range' "
         r"of size 256", IRError),
        ({"guard": [30, 3]}, r"= 69 is larger than axis 'doppler' of size 64", IRError),
        ({"axes": []}, r"field 'axes'.*at least 1 item", ChainFileError),
    ],
)
def test_cfar_rules(change: dict, match: str, cls: type[IRError]) -> None:
    node = {k: v for k, v in {**CFAR_OK, **change}.items() if v is not None}
    _fails(_chain(RD_SRC, node), "det", match, cls)


def test_cfar_pfa_needs_power() -> None:
    amp = _src({"range": 64})
    _fails(_chain(amp, {"id": "det", "op": "cfar", "input": "src", "kind": "ca", "guard": 1,
                        "train": 4, "pfa": 1e-3}),
           "det", r"pfa assumes square-law \(power\) input but the input domain is 'amplitude'")


def test_classifier_rules() -> None:
    _fails(_chain(_src({"range": 8}), {"id": "cls", "op": "classifier", "input": "src",
                                       "num_classes": 3, "weights": "w"}),
           "cls", r"at least 2 axes")
    _fails(_chain(_src(**SIG), {"id": "cls", "op": "classifier", "input": "src",
                                "num_classes": 1, "weights": "w"}),
           "cls", r"field 'num_classes'", ChainFileError)


def test_python_construction_errors_are_irerrors_naming_op_and_field() -> None:
    with pytest.raises(IRError, match=r"op 'window': field 'kind': Input should be 'hann'"):
        Window(axis="sample", kind="triangle")
    with pytest.raises(IRError, match=r"op 'cfar': field 'alpha'.*; field 'pfa'"):
        CFAR(kind="ca", guard=1, train=1, alpha=-1.0, pfa=2.0)
    with pytest.raises(IRError, match=r"op 'threshold': field 'value': Field required"):
        Threshold()  # type: ignore[call-arg]
    with pytest.raises(IRError, match=r"field 'gain': Extra inputs are not permitted"):
        Output(gain=2)  # type: ignore[call-arg]
