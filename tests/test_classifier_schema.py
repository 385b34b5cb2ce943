"""The classifier op's layer stack: shapes, weights keys, errors and chain-file round trips."""

from __future__ import annotations

import numpy as np
import pytest

from ir import Graph
from ir.errors import ChainFileError, IRError
from ir.ops.classify import (
    LIF,
    Classifier,
    Conv2d,
    Dense,
    Integrator,
    LevelsEncoding,
    Pool,
    Recurrent,
)
from ir.types import TensorType

STACK = (Conv2d(channels=4, kernel=(3, 3), stride=(2, 2), padding=(1, 1), neuron=LIF(dv=0.25)),
         Pool(mode="max", size=(2, 2)), Recurrent(units=6), Integrator(units=3))
OP = Classifier(num_classes=3, weights="w.npz", encoding=LevelsEncoding(levels=(10.0,)),
                layers=STACK)
ROI = TensorType(axes={"object": 5, "frame": 8, "doppler": 16, "range": 12}, domain="db")


def test_shapes_by_hand() -> None:
    # conv: (12 + 2 - 3)//2 + 1 = 6 range, (16 + 2 - 3)//2 + 1 = 8 doppler; pool: 3 x 4
    assert OP.feature_shapes("c", (12, 16)) == [(1, 12, 16), (4, 6, 8), (4, 3, 4), (6,), (3,)]
    assert OP.weight_shapes("c", (12, 16)) == {
        "layers.0.weight": (4, 1, 3, 3), "layers.2.weight": (6, 48),
        "layers.2.recurrent": (6, 6), "layers.3.weight": (3, 6)}
    out = OP.infer("c", [ROI])
    assert out.axes == {"object": 5, "class": 3} and OP.batch_axes(ROI) == ("object",)


@pytest.mark.parametrize(("layers", "match"), [
    (STACK[:3], r"layer 2 \(recurrent\): the integrator readout must be the last"),
    ((Dense(units=4), *STACK), r"layer 1 \(conv2d\): a map layer after a flat layer"),
    ((Conv2d(channels=2, kernel=(20, 3)), Integrator(units=3)),
     r"layer 0 \(conv2d\): maps an input of 12 x 16 to -7 x 14"),
    ((Pool(mode="avg", size=(13, 1)), Integrator(units=3)), r"layer 0 \(pool\).*0 x 16"),
    ((Integrator(units=4),), r"layer 0 \(integrator\): units = 4 but num_classes = 3"),
])
def test_bad_stacks_name_node_and_layer(layers: tuple, match: str) -> None:
    op = OP.model_copy(update={"layers": layers})
    with pytest.raises(IRError, match=r"node 'c' \(classifier\): " + match) as info:
        op.infer("c", [ROI])
    assert info.value.node == "c"


def test_missing_axes_and_levels() -> None:
    with pytest.raises(IRError, match=r"lack \['frame'\]"):
        OP.infer("c", [TensorType(axes={"range": 8, "doppler": 8})])
    with pytest.raises(IRError, match="levels must increase strictly"):
        LevelsEncoding(levels=(2.0, 1.0))
    with pytest.raises(IRError, match=r"field 'v_th'"):
        LIF(v_th=0.0)


def test_check_weights() -> None:
    good = {k: np.zeros(s) for k, s in OP.weight_shapes("c", (12, 16)).items()}
    assert set(OP.check_weights("c", (12, 16), good)) == set(good)
    with pytest.raises(IRError, match=r"missing keys \['layers.3.weight'\], unexpected keys "
                                      r"\['extra'\]"):
        OP.check_weights("c", (12, 16), {**{k: v for k, v in good.items()
                                              if k != "layers.3.weight"}, "extra": 1})
    bad = {**good, "layers.2.recurrent": np.full((6, 6), np.nan)}
    with pytest.raises(IRError, match=r"key 'layers.2.recurrent' \(layer 2, recurrent\) must "
                                      "hold finite"):
        OP.check_weights("c", (12, 16), bad)


def test_chain_round_trip_keeps_kind_tags() -> None:
    g = Graph.from_dict({"name": "c", "nodes": [
        {"id": "roi", "op": "input", "shape": dict(ROI.axes), "domain": "db"},
        {"id": "cls", "op": "classifier", "input": "roi", **OP.params()},
        {"id": "out", "op": "output", "input": "cls"}]})
    again = Graph.from_dict(g.to_dict())
    assert again.op("cls") == OP
    assert g.to_dict()["nodes"][1]["layers"][1] == {"kind": "pool", "mode": "max",
                                                    "size": [2, 2]}


def test_unknown_layer_kind_is_a_chain_error() -> None:
    with pytest.raises(ChainFileError, match="layers.0"):
        Graph.from_dict({"name": "c", "nodes": [
            {"id": "roi", "op": "input", "shape": dict(ROI.axes)},
            {"id": "cls", "op": "classifier", "input": "roi", "num_classes": 3,
             "weights": "w", "layers": [{"kind": "lstm", "units": 3}]}]})
