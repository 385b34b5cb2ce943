"""Placement across chips: hand-counted inter-chip traffic on a tiny board, the per-chip report,
board profiles, and invariants (every neuron once, no core or chip over its budget)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_alloc_split import allocate, networks, profiles

from compiler.hardware import BUILTIN_BOARDS, HardwareProfile, load_profile
from compiler.passes import CompileContext, run_pipeline
from compiler.passes.place import Place, place
from compiler.passes.place_chips import chip_assignment, chip_cut
from compiler.passes.report import ReportPass
from compiler.passes.split import Split
from compiler.program import CompiledProgram, Segment
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir import Graph
from ir.errors import BudgetError, CompileError

ROOT = Path(__file__).resolve().parents[1]
# two chips of three cores, two neurons per core; 16-bit messages over a 1 kbit/s link
BOARD = HardwareProfile(name="tiny-board", cores_per_chip=3, chips=2, neurons_per_core=2,
                        spike_message_bits=16, inter_chip_bandwidth_bit_s=1000.0,
                        inter_chip_latency_s=1e-3)


def chain() -> SpikingNetwork:
    """x -> a (identity) -> b (identity, heavy: a is a plain IF neuron, n_steps = 8 spikes
    bound per neuron) -> c (all-to-all, light: b fires once)."""
    once = NeuronParams(reset="fire_once")
    pops = [Population(id="x", shape={"i": 4}, source=True),
            Population(id="a", shape={"o": 4}, origin={"node": "A", "motif": "id"}),
            Population(id="b", shape={"o": 4}, params=once, origin={"node": "B", "motif": "id"}),
            Population(id="c", shape={"o": 4}, params=once, origin={"node": "C", "motif": "all"})]
    def mat(i, s, t, w):
        return MatrixProjection(id=i, source=s, target=t, contract=("o" if s != "x" else "i",),
                                produce=("o",), weights=w)
    return SpikingNetwork(name="c3", n_steps=8, populations=pops, projections=[
        mat("xa", "x", "a", np.eye(4)), mat("ab", "a", "b", np.eye(4)),
        mat("bc", "b", "c", np.ones((4, 4)))],
        encoders=[Encoder(port="x", population="x",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))]).validate()


def in_order(demand, limits, affinity, n_cores):
    return np.arange(len(demand))  # blocks a0 a1 b0 b1 c0 c1 on cores 0..5


def test_two_chips_hand_counted_traffic():
    net = chain()
    # Blocks (2 neurons each): a0 a1 b0 b1 c0 c1, one per core. Spikes per neuron (bound):
    # a 8 (plain IF, n_steps), b 1 (fire-once). Messages = distinct (destination core, source
    # neuron) pairs across cores x the source's spikes:
    #   a -> b (identity): b0's core receives a0, a1 from a0's core, b1's a2, a3: 4 x 8 = 32;
    #   b -> c (all-to-all): each c core receives all 4 b neurons from 2 other cores: 8 x 1 = 8.
    # inter_core = 40 whatever the chips.
    # The placer's order (chips {a0 a1 b0} {b1 c0 c1}) cuts a -> b at b1 (a2, a3 on the other
    # chip: 2 x 8 = 16) and b -> c at c0 and c1 (each gets b0's 2 neurons from chip 0: 4 x 1):
    # inter_chip = 20.
    kept = place([net], None, BOARD, placer=in_order, chip_assignment="placer")
    assert kept.traffic["inter_core"] == 40.0 and kept.traffic["inter_chip"] == 20.0
    # Keeping the heavy identity pairs on one chip ({a0 b0 c?} {a1 b1 c?}) leaves only the light
    # all-to-all across: each c core gets the 2 b neurons of the other chip: 2 + 2 = 4.
    pl = place([net], None, BOARD, placer=in_order)
    assert pl.traffic["inter_core"] == 40.0 and pl.traffic["inter_chip"] == 4.0
    chip = dict(zip([p + str(b) for _, p, b in pl.items], pl.chip.tolist(), strict=True))
    assert chip["a0"] == chip["b0"] != chip["a1"] == chip["b1"]
    assert pl.chip_messages.tolist() == [[pl.chip_messages[0, 0], 2.0],
                                         [2.0, pl.chip_messages[1, 1]]]
    assert np.bincount(pl.chip).tolist() == [3, 3]
    # the default placer finds the same cut
    assert place([net], None, BOARD).traffic["inter_chip"] == 4.0


def test_per_chip_report_table():
    prog = CompiledProgram(graph=Graph.from_yaml(ROOT / "examples/chains/carrada_rd_oscfar.yaml"),
                           segments=[Segment(kind="spiking", inputs=[], outputs=[],
                                             network=chain())])
    run_pipeline([Split(), Place(), ReportPass(frame_rate_hz=10.0)],
                 CompileContext(target=BOARD), prog)
    data = prog.records["report"].data
    rows = {r["chip"]: r for r in data["chips"]}
    # each chip: 3 cores, 6 neurons; 2 messages in and 2 out per frame; at 16 bits and
    # 10 frames/s: 2 x 16 x 10 = 320 bit/s each way, 0.32 of the 1 000 bit/s link
    for r in rows.values():
        assert (r["cores"], r["neurons"], r["in"], r["out"]) == (3, 6, 2.0, 2.0)
        assert (r["in_bit_s"], r["out_bit_s"], r["link_utilisation"]) == (320.0, 320.0, 0.32)
    x = data["inter_chip"]
    assert (x["chips"], x["messages_per_frame"], x["bit_s"]) == (2, 4.0, 640.0)
    # added latency: 8 steps (one run of 8) x 1 ms + the busiest link's 2 x 16 bit / 1 000 bit/s
    assert x["crossing_steps"] == 8 and x["added_latency_s"] == pytest.approx(8e-3 + 0.032)
    md = prog.records["report"].to_markdown()
    assert "## Chips: 2 used" in md and "| 0 | 3 | 6 |" in md


def test_single_chip_report_has_no_chip_table():
    prog = CompiledProgram(graph=Graph.from_yaml(ROOT / "examples/chains/carrada_rd_oscfar.yaml"),
                           segments=[Segment(kind="spiking", inputs=[], outputs=[],
                                             network=chain())])
    run_pipeline([Split(), Place(), ReportPass()], CompileContext(target="loihi"), prog)
    data = prog.records["report"].data
    assert "chips" not in data and "inter_chip" not in data
    assert prog.records["placement"].chip_messages is None


@pytest.mark.parametrize("name", BUILTIN_BOARDS)
def test_boards_keep_their_chips_budgets_and_cite_every_figure(name):
    board = load_profile(name)
    chip = load_profile(board.chip_profile)
    keep = set(HardwareProfile.model_fields) - {"name", "description", "chips", "cores_per_chip",
                                                "chip_profile", "inter_chip_bandwidth_bit_s",
                                                "inter_chip_latency_s", "spike_message_bits"}
    assert {k: getattr(board, k) for k in keep} == {k: getattr(chip, k) for k in keep}
    assert board.chips > 1 and board.cores_per_chip <= chip.cores_per_chip
    text = (ROOT / "compiler" / "hardware" / "boards" / f"{name}.yaml").read_text()
    fields = [ln for ln in text.splitlines() if ln[:1].isalpha()]
    assert all("#" in ln for ln in fields if not ln.startswith(("name:", "description:")))
    assert "http" in text  # a published source for the chip count
    for ln in fields:  # the link figures are not published: each says it is an assumption
        if ln.startswith(("inter_chip", "spike_message")):
            assert "assumption" in ln
    # saved with a program and read back, a board is the same profile
    assert HardwareProfile.model_validate(board.model_dump(mode="json")) == board


def test_a_board_cannot_loosen_its_chip(tmp_path):
    f = tmp_path / "b.yaml"
    f.write_text("name: b\nchip_profile: loihi\nchips: 4\nneurons_per_core: 4096\n")
    with pytest.raises(CompileError, match="cannot set neurons_per_core"):
        load_profile(f)
    f.write_text("name: b\nchip_profile: loihi\nchips: 4\ncores_per_chip: 256\n")
    with pytest.raises(CompileError, match="exceeds the 128 cores of one loihi chip"):
        load_profile(f)
    f.write_text("name: b\nchip_profile: kapoho_point\nchips: 4\n")
    with pytest.raises(CompileError, match="built-in chip profile.*not a board"):
        load_profile(f)
    f.write_text("name: b\nchip_profile: loihi\nchips: 4\nunbounded: true\n")  # no links
    assert load_profile(f).n_cores == 512
    # single-chip profiles serialise without the board fields (saved artifacts unchanged)
    assert "chip_profile" not in load_profile("loihi").model_dump(mode="json")
    with pytest.raises(CompileError, match="chip_assignment"):
        Place(chip_assignment="random")


@given(networks(), profiles(), st.sampled_from(("spatial", "auto")))
@settings(max_examples=40, deadline=None)
def test_every_neuron_once_no_core_or_chip_over_budget(net, profile, mode):
    try:
        rec, pl = allocate(net, profile, mode)
    except BudgetError:
        return
    assert sorted(pl.items) == sorted({*pl.items})  # each block placed once, on one core
    for pid, dem in rec.demand.items():  # blocks cover each population's neurons once
        e = dem.blocks.edges
        assert e[0] == 0 and np.all(np.diff(e) > 0)
        assert len([i for i in pl.items if i[1] == pid]) == dem.blocks.n_blocks
    assert np.all(pl.usage <= profile.limits())                 # no core over a budget
    cores_on = np.bincount(np.unique(pl.core) // profile.cores_per_chip)
    assert np.all(cores_on <= profile.cores_per_chip)         # no chip over its cores
    assert pl.n_chips <= profile.chips
    assert sorted(np.unique(pl.core).tolist()) == list(range(pl.n_cores))
    if pl.chip_messages is not None:  # the chip matrix agrees with the traffic count
        m = pl.chip_messages
        assert m.sum() - np.trace(m) == pytest.approx(pl.traffic["inter_chip"])


@given(st.integers(2, 12), st.integers(1, 4), st.data())
@settings(max_examples=60, deadline=None)
def test_chip_assignment_is_a_permutation_never_worse_than_the_order(n, cpc, data):
    vals = data.draw(st.lists(st.integers(0, 5), min_size=n * n, max_size=n * n))
    m = np.array(vals, dtype=float).reshape(n, n)
    np.fill_diagonal(m, 0)
    new = chip_assignment(m, cpc)
    assert sorted(new.tolist()) == list(range(n))
    w = m + m.T
    assert chip_cut(w, new // cpc) <= chip_cut(w, np.arange(n) // cpc)
