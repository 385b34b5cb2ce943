"""Repetitions: stages and instances, the auto/spatial/temporal plans, hand-worked traffic."""

from __future__ import annotations

import numpy as np
import pytest

from compiler.hardware import HardwareProfile, load_profile
from compiler.hardware.reference_networks import dft_network, os_cfar_network
from compiler.hardware.repetition import instance_neurons, stages
from compiler.passes.base import CompileContext
from compiler.passes.place import Place, place
from compiler.passes.split import (
    Split,
    multiplex_candidates,
    repetition_mode,
    split,
    split_program,
)
from compiler.program import CompiledProgram, Segment
from compiler.snn import (
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Population,
    SpikingNetwork,
)
from ir.errors import BudgetError, CompileError

CODE = LatencyCode(t_max=8, x_min=0.0, x_max=1.0)
ONCE = NeuronParams(reset="fire_once")


def two_stage(w_b: np.ndarray | None = None) -> SpikingNetwork:
    """x{r:2,i:2} -identity-> a{r:2,o:2} (stage A) -w_b-> b{r:2,q} (stage B), fire-once."""
    w_b = np.ones((2, 2)) if w_b is None else w_b
    n_q = w_b.shape[1]
    return SpikingNetwork(name="ab", n_steps=8, populations=[
        Population(id="x", shape={"r": 2, "i": 2}, source=True),
        Population(id="a", shape={"r": 2, "o": 2}, params=ONCE, origin={"node": "A"}),
        Population(id="b", shape={"r": 2, "q": n_q}, params=ONCE, origin={"node": "B"})],
        projections=[
            MatrixProjection(id="xa", source="x", target="a", contract=("i",), produce=("o",),
                             weights=np.eye(2)),
            MatrixProjection(id="ab", source="a", target="b", contract=("o",), produce=("q",),
                             weights=w_b)],
        encoders=[Encoder(port="x", population="x", code=CODE)]).validate()


def run(net, profile, mode="auto"):
    prog = CompiledProgram(graph=None, segments=[
        Segment(kind="spiking", inputs=[], outputs=[], network=net)])
    ctx = CompileContext(target=profile)
    return Place(repetitions=mode).apply(ctx, Split(repetitions=mode).apply(ctx, prog))


def test_stages_axes_and_instances_by_hand():
    net = dft_network({"rx": 2, "chirp": 3}, 4)
    (st,) = stages(net)
    # rng{rx:2, chirp:3, range:4, part:4}: the matrix contracts (sample, part) and produces
    # (range, part), so it repeats over rx x chirp = 6
    assert (st.key, st.repetitions, st.axes, st.multiplexable) == ("rng", 6, ("rx", "chirp"),
                                                                   True)
    assert st.neurons == 96 and st.synapse_instances == 6 * 8 * 16
    assert instance_neurons(net.population["rng"], st.axes).tolist() == list(range(16))
    p = Population(id="p", shape={"a": 2, "r": 2, "b": 3})
    assert instance_neurons(p, ("a", "b")).tolist() == [0, 3]
    # a stencil stage counts one repetition: never multiplexed
    (cfar,) = stages(os_cfar_network(16, 32))
    assert (cfar.repetitions, cfar.axes, cfar.multiplexable) == (1, (), False)


def test_dense_dft_on_loihi_is_multiplexed_by_auto():
    net = dft_network()  # 4 x 64 repetitions of a dense 512 x 1024 matrix
    loihi = load_profile("loihi")
    with pytest.raises(BudgetError, match=r"3,072 cores.*time-multiplex the 1 repeated stage"):
        split_program([net], loihi, "spatial")
    prog = run(net, loihi)
    (rec,) = prog.records["split"]
    assert rec.multiplexed == {"rng": 256} and rec.runs("rng") == 256
    dem = rec.demand["rng"]
    # one instance: 256 range x 4 parts = 1 024 neurons and 512 x 1 024 synapses (x 24 bit:
    # 12 Mbit, at least 12 cores of 1 Mbit; 1 024 neurons per core)
    assert dem.blocks.n_neurons == 1024 and int(dem.entries.sum()) == 512 * 1024
    assert dem.blocks.n_blocks >= 12
    pl = prog.records["placement"]
    assert pl.multiplexed == [{"network": "dft", "stage": "rng", "repetitions": 256}]
    assert np.all(pl.usage <= loihi.limits())
    # every instance run reads its 512 inputs: messages from the host = 256 runs x 512 inputs
    # x 1 spike (latency code) x (distinct destination cores of each input)
    assert pl.traffic["host_input"] % (256 * 512) == 0 and pl.traffic["buffered"] == 0


def test_auto_stays_spatial_when_it_fits_and_temporal_multiplexes_all():
    net = two_stage()
    roomy = HardwareProfile(name="roomy", cores_per_chip=4, chips=1, neurons_per_core=2)
    assert run(net, roomy).records["split"][0].multiplexed == {}
    rec = run(net, roomy, "temporal").records["split"][0]
    assert rec.multiplexed == {"A": 2, "B": 2}
    assert [d.blocks.neurons.tolist() for d in rec.demand.values()] == [[0, 1], [0, 1]]


def test_hand_worked_multiplexed_traffic_and_buffer():
    # 3 cores of 2 neurons: spatial needs 8 neurons > 6; A and B tie (4 neurons, 2 reps), so
    # auto multiplexes A (network order): a instance 2 neurons + b 4 = 6 neurons on 3 cores
    prof = HardwareProfile(name="three", cores_per_chip=3, chips=1, neurons_per_core=2)
    net = two_stage()
    assert [s.key for _, s in multiplex_candidates([net], prof)] == ["A", "B"]
    prog = run(net, prof)
    rec, pl = prog.records["split"][0], prog.records["placement"]
    assert rec.multiplexed == {"A": 2} and rec.runs("a") == 2 and rec.runs("b") == 1
    assert not rec.on_chip("a", "b") and not rec.on_chip("x", "a")
    assert pl.n_cores == 3
    # x -> a: the a-instance block reads x[0, 0], x[0, 1], once per run: 2 x 2 = 4 host messages
    # a -> b: b-block r=0 reads a[0, :], block r=1 reads a[1, :] from the frame buffer: 4
    assert pl.traffic["host_input"] == 4.0 and pl.traffic["buffered"] == 4.0
    assert pl.traffic["inter_core"] == 0.0


def test_fan_in_sum_over_cores_rejects_the_spatial_plan():
    # 8 neurons fit one core's neuron budget, so the totals check passes; but a dense 4 x 4
    # matrix per repetition needs 8 fan-in lines (limit 4): the split's blocks sum to 8 > 4
    # lines on the one core. One instance reads 4 sources: 1 block.
    net = SpikingNetwork(name="fan", n_steps=4, populations=[
        Population(id="x", shape={"r": 2, "i": 4}, source=True),
        Population(id="a", shape={"r": 2, "o": 4}, origin={"node": "A", "motif": "dense"})],
        projections=[MatrixProjection(id="w", source="x", target="a", contract=("i",),
                                      produce=("o",), weights=np.ones((4, 4)))],
        encoders=[Encoder(port="x", population="x", code=CODE)]).validate()
    prof = HardwareProfile(name="one", cores_per_chip=1, chips=1, neurons_per_core=8,
                           input_axons_per_core=4)
    with pytest.raises(BudgetError, match=r"node 'A' \(motif dense.*time-multiplex the 1"):
        run(net, prof, "spatial")
    assert split_program([net], prof)[0].multiplexed == {"A": 2}
    prog = run(net, prof)
    assert prog.records["split"][0].multiplexed == {"A": 2}
    # 4 neurons, 4 fan-in lines, no fan-out, 16 synapses x 64 bit (default entry width)
    assert prog.records["placement"].usage.tolist() == [[4, 4, 0, 16 * 64]]


def test_place_escalates_when_blocks_do_not_pack():
    # 2 cores of 3 neurons; spatial: a (4 neurons) -> 2 blocks of 2, b (2) -> 1 block of 2:
    # 6 neurons <= 6 pass every sum, but three blocks of 2 do not pack into two cores of 3.
    # The place pass multiplexes A (the larger stage): a instance 2 + b 2 -> 2 cores.
    net = two_stage(np.ones((2, 1)))
    prof = HardwareProfile(name="pair", cores_per_chip=2, chips=1, neurons_per_core=3)
    assert split_program([net], prof)[0].multiplexed == {}  # what the split alone decides
    with pytest.raises(BudgetError, match=r"3 blocks .* do not fit on 2 cores.*time-multiplex"):
        run(net, prof, "spatial")
    prog = run(net, prof)
    assert prog.records["split"][0].multiplexed == {"A": 2}
    assert prog.records["placement"].usage[:, 0].tolist() == [2, 2]


def test_nothing_repeated_left_to_multiplex_says_so():
    prof = HardwareProfile(name="tiny", cores_per_chip=1, chips=1, neurons_per_core=1)
    with pytest.raises(BudgetError, match=r"needs 4 neurons.*tiny.*even with every repeated "
                       r"stage time-multiplexed \(one instance each of A x2, B x2\)") as e:
        run(two_stage(), prof)
    assert e.value.node in ("A", "B")


def test_bad_options_raise_compile_error():
    with pytest.raises(CompileError, match=r"'repetitions' = 'sometimes' is not one of auto"):
        repetition_mode("sometimes")
    with pytest.raises(CompileError, match=r"'repetitions' = 'sometimes' is not one of auto"):
        Split(repetitions="sometimes")  # refused when the pipeline is made, before any pass runs
    assert repetition_mode("auto") == "auto"
    with pytest.raises(CompileError, match=r"stage 'det' cannot be time-multiplexed"):
        split(os_cfar_network(16, 32), multiplexed={"det"})


def test_placing_a_multiplexed_split_directly():
    net = two_stage()
    rec = split(net, multiplexed={"B"})
    assert rec.blocks["b"].n_neurons == 2 and rec.blocks["a"].n_neurons == 4
    pl = place([net], [rec])
    # unbounded: one block each; a -> b crosses into the multiplexed B: 2 runs x 2 sources
    assert pl.traffic["buffered"] == 4.0 and pl.traffic["inter_core"] == 0.0
