"""A measured compile does shared work once, and compiles the same bytes (issue 35).

The attempts of a measured compile share one :class:`compiler.memo.CompileMemo`: the
time-coded DFT's rounding (``rint_feedback``), networks equal in content (reused objects,
so their blocks' demand and simulation plans are kept) and their splits.  The memo must
change how often the work is done, never what it gives: the program, the placement and
the motif selection of a compile with the memo are those of one that recomputes it all.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import compiler.compile as compile_module
from backends import save
from backends.reference import ReferenceSimulator
from compiler.memo import CompileMemo, network_digest
from compiler.quantize_weights import rint_feedback
from compiler.snn.examples import tiny_network
from ir import Graph
from radar.config import preset
from radar.scene import SCENE_PRESETS, simulate_frame

CHAIN = "examples/chains/carrada_rd_oscfar.yaml"


class _Recorded(CompileMemo):
    """The memo, remembered so the test can read its hits."""

    made: list[CompileMemo] = []

    def __init__(self) -> None:
        super().__init__()
        _Recorded.made.append(self)


class _NoReuse(CompileMemo):
    """A memo that computes every result again (what a compile without one does)."""

    def rint_feedback(self, x, h, w_max):
        return rint_feedback(x, h, w_max)

    def network(self, network):
        return network

    def split(self, network, profile, multiplexed, compute):
        return compute()

    def kept(self, kind, owners, key, compute):
        return compute()


def _artifact_bytes(program, folder) -> dict[str, bytes]:
    save(program, folder)
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def _frames(graph: Graph) -> np.ndarray:
    from radarsnn.bench import chain_inputs

    config, scene = preset("carrada"), SCENE_PRESETS["carrada"]()
    return np.stack([chain_inputs(graph, simulate_frame(config, scene, seed=s).adc)
                     for s in range(1, 4)])


def _preset_chain() -> Graph:
    from compiler.chains import range_doppler_chain

    return range_doppler_chain(preset("carrada"))


@pytest.mark.parametrize(("chain", "reused"), [(lambda: Graph.from_yaml(CHAIN), True),
                                               (_preset_chain, False)],
                         ids=["carrada_rd_oscfar", "carrada_preset"])
def test_the_memo_compiles_the_bytes_of_a_compile_without_it(chain, reused, tmp_path,
                                                              monkeypatch):
    graph = chain()
    cal = {"adc": _frames(graph)}
    _Recorded.made.clear()
    monkeypatch.setattr(compile_module, "CompileMemo", _Recorded)
    shared = compile_module.compile_graph(graph, "kapoho_point", calibration_inputs=cal,
                                          simulator=ReferenceSimulator())
    (memo,) = _Recorded.made
    if reused:  # the DFTs stay while the CFAR climbs: their work is done once
        assert all(memo.hits[k] > 0 for k in ("rint_feedback", "network", "split",
                                              "traffic", "real_weights")), memo.hits
    monkeypatch.setattr(compile_module, "CompileMemo", _NoReuse)
    alone = compile_module.compile_graph(graph, "kapoho_point", calibration_inputs=cal,
                                         simulator=ReferenceSimulator())
    selection = shared.records.extra["motif_selection"]
    assert len(selection["attempts"]) > 1
    assert selection == alone.records.extra["motif_selection"]
    assert shared.records.accuracy.to_dict() == alone.records.accuracy.to_dict()
    assert shared.records.placement.to_dict() == alone.records.placement.to_dict()
    assert np.array_equal(shared.records.placement.core, alone.records.placement.core)
    for a, b in zip(shared.records.splits, alone.records.splits, strict=True):
        assert a.multiplexed == b.multiplexed and a.stage_of == b.stage_of
        assert list(a.demand) == list(b.demand)
        for pid in a.demand:
            assert np.array_equal(a.demand[pid].amounts, b.demand[pid].amounts)
            assert np.array_equal(a.demand[pid].blocks.edges, b.demand[pid].blocks.edges)
    assert _artifact_bytes(shared, tmp_path / "shared") == _artifact_bytes(alone,
                                                                         tmp_path / "alone")


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 12), st.integers(1, 5), st.integers(0, 2 ** 32 - 1),
       st.sampled_from([1.0, 3.0, 127.0]))
def test_the_memo_rounds_as_rint_feedback_bit_for_bit(n_in, n_out, seed, w_max):
    rng = np.random.default_rng(seed)
    x = rng.normal(scale=w_max, size=(n_in, n_out))
    v = rng.normal(size=(n_in, 2 * n_in))
    h = v @ v.T
    memo = CompileMemo()
    first = memo.rint_feedback(x, h, w_max)
    want = rint_feedback(x, h, w_max)
    assert first.tobytes() == want.tobytes() and first.dtype == want.dtype
    again = memo.rint_feedback(x.copy(), h.copy(), w_max)
    assert again is first and memo.hits["rint_feedback"] == 1
    assert not first.flags.writeable  # nobody can change what a later attempt reads
    other = x.copy()
    other[0, 0] += 0.5
    assert memo.rint_feedback(other, h, w_max).tobytes() == rint_feedback(other, h,
                                                                          w_max).tobytes()
    assert memo.rint_feedback(x, h, w_max + 1) is not first


@settings(max_examples=25, deadline=None)
@given(arrays(np.float64, (3, 2), elements=st.floats(-4, 4, allow_nan=False)))
def test_the_network_digest_follows_every_weight(weights):
    net = tiny_network(n_steps=4)
    (proj,) = [p for p in net.projections if hasattr(p, "weights")][:1]
    changed = dataclasses.replace(proj, weights=np.asarray(proj.weights) + 1.0)
    other = tiny_network(n_steps=4)
    other.projections = [changed if p is proj else p for p in net.projections]
    assert network_digest(net) == network_digest(tiny_network(n_steps=4))
    assert network_digest(other) != network_digest(net)
    memo = CompileMemo()
    assert memo.network(net) is net and memo.network(other) is other
    assert memo.network(tiny_network(n_steps=4)) is net and memo.hits["network"] == 1


def test_the_digest_keeps_axis_order_and_refuses_what_it_cannot_read():
    a, b = tiny_network(n_steps=4), tiny_network(n_steps=4)
    b.meta = {"x": 1, "y": 2}
    a.meta = {"y": 2, "x": 1}
    assert network_digest(a) != network_digest(b)
    a.meta = {"opaque": object()}
    assert network_digest(a) is None
    memo = CompileMemo()
    assert memo.network(a) is a and memo.network(a) is a and memo.hits["network"] == 0


def test_the_spike_traffic_of_a_placement_is_the_same_with_the_memo():
    from compiler.hardware import load_profile
    from compiler.hardware.reference_networks import dft_network
    from compiler.passes.place import place
    from compiler.passes.split import split_program

    net, profile, memo = dft_network(), load_profile("loihi"), CompileMemo()
    alone = place([net], split_program([net], profile), profile)
    fresh = place([net], split_program([net], profile), profile, memo=memo)
    assert memo.hits["traffic"] == 0  # another split record: nothing to reuse
    splits = split_program([net], profile)
    kept = [place([net], splits, profile, memo=memo) for _ in range(2)]
    assert memo.hits["traffic"] == 1
    assert alone.traffic == fresh.traffic == kept[0].traffic == kept[1].traffic
    assert all(type(v) is type(alone.traffic[k]) for k, v in kept[1].traffic.items())
    assert np.array_equal(alone.core, kept[1].core)


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 9), st.integers(1, 9), st.integers(0, 2 ** 32 - 1),
       st.sampled_from(["none", "re_im", "signed", "re_im_signed"]))
def test_the_memo_makes_a_dft_layers_real_weights_as_real_weights_does(n_out, n_in, seed,
                                                                        in_split):
    from compiler.lowering.dft_common import real_weights

    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n_out, n_in)) + 1j * rng.normal(size=(n_out, n_in))
    memo = CompileMemo()
    made = memo.of_arrays("real_weights", (w,), (in_split, "re_im"),
                          lambda: real_weights(w, in_split, "re_im"))
    assert made.tobytes() == real_weights(w, in_split, "re_im").tobytes()
    assert not made.flags.writeable
    again = memo.of_arrays("real_weights", (w.copy(),), (in_split, "re_im"),
                           lambda: real_weights(w, in_split, "re_im"))
    assert again is made and memo.hits["real_weights"] == 1
    other = memo.of_arrays("real_weights", (w,), (in_split, "signed"),
                           lambda: real_weights(w, in_split, "signed"))
    assert other is not made


def test_a_split_is_kept_per_network_profile_and_stages():
    memo, net, calls = CompileMemo(), tiny_network(n_steps=4), []

    def compute():
        calls.append(1)
        return object()

    first = memo.split(net, "p", ("a",), compute)
    assert memo.split(net, "p", ("a",), compute) is first and len(calls) == 1
    assert memo.split(net, "p", ("a", "b"), compute) is not first
    assert memo.split(tiny_network(n_steps=4), "p", ("a",), compute) is not first
    assert len(calls) == 3


if __name__ == "__main__":
    pytest.main([__file__])
