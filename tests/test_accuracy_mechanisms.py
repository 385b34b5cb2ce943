"""The accuracy contract fires, naming the stage, on each way a spiking chain loses targets.

One small scene of the project's simulator per mechanism, compiled with the explicit
configuration that loses the data and ``accuracy="error"``: the compile raises
:class:`~ir.errors.AccuracyError` naming that stage's node and the figure that breaks;
``accuracy="warn"`` keeps the configuration and records the figure in the program; the
default (``motifs="auto"``) holds or climbs to a configuration that does.

1. the time-coded S-FT's constant read-out code (range DFT) decodes the noise floor to 0
   (half of the cells of a profile spanning ~57 dB);
2. the time-coded Doppler S-FT on a target without graded spikes does the same to a map
   spanning ~68 dB (the range DFT on the resonator, which holds);
3. the S-FT's input time code on a 1-D chirp sequence without the static split: its step
   lifts the range profile's noise floor (leakage sets the code's scale);
4. the resonator's linear time read-out, scaled per bin on the calibration frames, clips
   a new frame's target in a bin that held noise there;
5. the spiking CA-CFAR on linear power misses most targets.
"""

from __future__ import annotations

import numpy as np
import pytest

import radarsnn
from compiler.chains import CA_CFAR, range_cfar_chain, range_chain, range_doppler_chain
from ir import Graph
from ir.errors import AccuracyError
from radar.config import preset
from radar.scene import simulate_frame
from radar.scene_cases import SCENE_CASES
from radar.scene_model import Leakage, Scene, Target
from radar.sensor import RadarConfig

#: mimo77's 12-bit IQ front end, one channel, 16 chirps x 64 samples (a fast test map).
SMALL = RadarConfig(**{**preset("mimo77").model_dump(), "n_samples": 64, "n_chirps": 16,
                       "tx_positions_lambda": (0.0,), "rx_positions_lambda": (0.0,),
                       "name": "mimo77-small"})

#: The Tx->Rx coupling at range 0, near full scale (-8 dBFS per rail), as in leaky_mimo.
COUPLING = Leakage(range_m=0.0, amplitude_dbfs=-8.0, phase_deg=30.0, phase_noise_deg=0.05,
                   name="coupling")


def _target(range_bin: float, velocity_mps: float, amplitude_dbfs: float,
            config: RadarConfig = SMALL) -> Target:
    """A target whose per-rail amplitude is ``amplitude_dbfs`` (the scene's gain is -20 dBFS)."""
    range_m = range_bin * config.range_resolution_m
    return Target(range_m=range_m, velocity_mps=velocity_mps,
                  rcs_dbsm=float(amplitude_dbfs + 20.0 + 40 * np.log10(range_m)), name="t")


def _scene(seed: int, levels_dbfs: tuple[float, float], n: int = 3, *,
           leakage: Leakage | None = COUPLING, extra: tuple[Target, ...] = (),
           config: RadarConfig = SMALL) -> Scene:
    """``n`` targets drawn by ``seed`` at ``levels_dbfs`` (low, high), noise at -65 dBFS."""
    rng = np.random.default_rng([seed, 7])
    targets = tuple(_target(rng.uniform(8, 55), rng.uniform(-6, 6), rng.uniform(*levels_dbfs),
                            config) for _ in range(n))
    return Scene(targets=targets + extra, leakage=() if leakage is None else (leakage,),
                 noise_dbfs=-65.0, gain_dbfs=-20.0)


def _frames(scenes: list[Scene], seeds: tuple[int, ...], config: RadarConfig = SMALL
            ) -> np.ndarray:
    return np.stack([simulate_frame(config, s, seed=k).adc for s, k in zip(scenes, seeds,
                                                                            strict=True)])


def _refused(graph: Graph, target: str, **kwargs) -> AccuracyError:
    with pytest.raises(AccuracyError) as err:
        radarsnn.compile_graph(graph, target, accuracy="error", **kwargs)
    return err.value


def _kept(graph: Graph, target: str, **kwargs):
    """The same compile with ``accuracy="warn"``: the program and its first failing stage."""
    program = radarsnn.compile_graph(graph, target, accuracy="warn", **kwargs)
    (stage, why), *_ = program.records.accuracy.failing()
    return program, stage, why


# 1. The S-FT's constant read-out code on a range profile spanning ~57 dB ------------------

SEEDS = (100, 101, 102)  # the last one is held back for the check

#: SMALL with 4 chirps (the range DFT's gain lifts the profile 16 dB over the per-sample ratio).
PROFILE = RadarConfig(**{**SMALL.model_dump(), "n_chirps": 4,
                         "name": "mimo77-profile"})


def _profiles() -> np.ndarray:
    """A coupling 41 dB over the noise per sample, targets 20-45 dB below it: the input code
    (~48 dB) holds the samples, the range profile spans ~57 dB."""
    quiet = COUPLING.model_copy(update={"amplitude_dbfs": -24.0})
    return _frames([_scene(s, (-69.0, -44.0), leakage=quiet, config=PROFILE) for s in SEEDS],
                   SEEDS, PROFILE)


def test_1_the_s_ft_constant_read_out_decodes_the_noise_to_zero_and_is_named():
    g, frames = range_chain(PROFILE), _profiles()
    # output_spikes='time': the range values leave through the T-step charging read-out, as
    # they do into a spiking Doppler stage (a graded read-out applies only to host outputs)
    read_out = {"output_spikes": "time"}
    pinned = dict(motifs={"rng": "time"}, options={**read_out, "charging": "constant"},
                  calibration_inputs={"adc": frames})
    err = _refused(g, "loihi2", **pinned)
    assert err.node == "rng" and "stage 'rng'" in str(err)
    assert "dB re noise > -10 dB" in str(err)  # the noise floor is gone
    assert "with the motifs given" in str(err)  # nothing was searched: no empty rung list
    program, stage, why = _kept(g, "loihi2", **pinned)
    assert program.records.motifs["rng"] == "time" and stage.node == "rng"
    assert stage.figures["error_db"] > -8.0 and stage.figures["zero_fraction"] > 0.2
    assert any("error" in w for w in why)
    auto = radarsnn.compile_graph(g, "loihi2", options=read_out,
                                  calibration_inputs={"adc": frames})
    assert auto.records.accuracy.holds and auto.records.motifs["rng"] == "time"
    (stage,) = auto.records.accuracy.stages  # the calibrated charging schedule keeps the floor
    assert stage.figures["error_db"] < -10 and stage.figures["zero_fraction"] < 0.1


# 2. The time-coded Doppler read-out on a target without graded spikes ----------------------

def _range_doppler() -> Graph:
    """range_doppler_chain's DFTs, the Doppler spectrum read out (no CFAR)."""
    nodes = [n for n in range_doppler_chain(SMALL).to_dict()["nodes"]
             if n["id"] in ("adc", "win", "rng", "dwin", "dop")]
    return Graph.from_dict({"name": "rd", "nodes": [
        *nodes, {"id": "out", "op": "output", "input": "dop"}]})


def test_2_the_time_coded_doppler_read_out_is_named():
    # one target 45 dB over the noise per sample, ~68 dB on the map, two 20 and 40 dB weaker
    scenes = [_scene(s, (-20.0, -20.0), n=1, leakage=None,
                     extra=(_target(20.0 + s - 100, -3.0, -40.0),
                            _target(45.0 - s + 100, 4.0, -60.0))) for s in SEEDS]
    frames = _frames(scenes, SEEDS)
    # the range DFT on the resonator (it holds here), the Doppler DFT time-coded and read out
    # through its T-step time code (output_spikes='time': what a chip without graded spikes
    # does; a graded read-out does not save it either: the range values enter the Doppler
    # layer through the same time code)
    pinned = dict(motifs={"rng": "resonator", "dop": "time"},
                  calibration_inputs={"adc": frames}, options={"output_spikes": "time"})
    err = _refused(_range_doppler(), "spinnaker2", **pinned)
    assert err.node == "dop" and "stage 'dop'" in str(err) and "dB re noise" in str(err)
    program, stage, _ = _kept(_range_doppler(), "spinnaker2", **pinned)
    assert (stage.node, stage.motif, stage.upstream) == ("dop", "time", ("rng",))
    # the noise floor is gone: a third of the Doppler cells decode to 0, the rest to a step
    assert stage.figures["error_db"] > -3.0 and stage.figures["zero_fraction"] > 0.25
    assert program.records.report.data["accuracy"]["holds"] is False
    # the default on loihi2 climbs from the S-FT to the resonator DFTs, which keep the floor
    auto = radarsnn.compile_graph(_range_doppler(), "loihi2", calibration_inputs={"adc": frames})
    attempts = auto.records.extra["motif_selection"]["attempts"]
    assert auto.records.accuracy.holds and auto.records.motifs["dop__moving"] == "resonator"
    assert attempts[0]["config"] == {"dft": "time"} and attempts[0]["holds"] is False


# 3. The S-FT's input time code on a 1-D chirp sequence without the static split ------------

CHIRPS = RadarConfig(**{**preset("chirpseq").model_dump(), "n_samples": 128, "n_chirps": 16,
                        "name": "chirpseq-small"})


def _chirp_sequences() -> np.ndarray:
    """chirp_sequence_1d's draw (leakage 50 dB above the target) with a receiver 10 dB quieter:
    the leakage is 55 dB over the noise per sample, above the input code's ~48 dB."""
    case = SCENE_CASES["chirp_sequence_1d"]
    scenes = []
    for s in SEEDS:
        scene = case.draw(CHIRPS, np.random.default_rng([s, 34]))
        scenes.append(scene.model_copy(update={"noise_dbfs": scene.noise_dbfs - 10.0}))
    return _frames(scenes, SEEDS, CHIRPS)


def test_3_the_input_time_code_on_a_chirp_sequence_lifts_the_floor_and_is_named():
    g, frames = range_cfar_chain(CHIRPS), _chirp_sequences()
    pinned = dict(motifs={"dft": "time"}, options={"static_split": "off"},
                  calibration_inputs={"adc": frames})
    err = _refused(g, "loihi2", **pinned)
    assert err.node == "rng" and "stage 'rng'" in str(err) and "dB re noise" in str(err)
    program, stage, _ = _kept(g, "loihi2", **pinned)
    assert stage.node == "rng" and program.records.get("static-split") in (None, [])
    # the floor is lifted (rounding noise of the input code), not decoded to 0
    assert stage.figures["zero_fraction"] == 0.0 and stage.figures["error_db"] > -3.0
    failing = [s.node for s, _ in program.records.accuracy.failing()]
    assert failing[0] == "rng"  # named before the CFAR behind it, which also misses cells
    auto = radarsnn.compile_graph(g, "loihi2", calibration_inputs={"adc": frames})
    assert auto.records.accuracy.holds and auto.records.motifs["rng__moving"] == "time"


# 4. The resonator's linear time read-out clips a new frame's target ------------------------

def test_4_the_resonator_time_read_out_clips_a_new_target_and_is_named():
    cal = _frames([_scene(s, (-60.0, -45.0)) for s in SEEDS[:2]], SEEDS[:2])
    # the new frame: a target 25 dB over the calibration's strongest, in a bin that held
    # noise there, below the coupling (so the input code, scaled on the coupling, holds it)
    new = _frames([_scene(103, (-60.0, -45.0), extra=(_target(30.3, 2.0, -20.0),))], (103,))
    pinned = dict(motifs={"rng": "resonator"}, options={"resonator_readout": "time"},
                  calibration_inputs={"adc": cal}, check_inputs={"adc": new})
    g = range_chain(SMALL)
    err = _refused(g, "loihi2", **pinned)
    assert err.node == "rng" and "stage 'rng'" in str(err) and "lost" in str(err)
    _, stage, why = _kept(g, "loihi2", **pinned)
    assert stage.motif == "resonator" and stage.clipped == 0.0  # the inputs are not clipped
    assert stage.figures["lost"] > 0.1 and why == [w for w in why if w.startswith("lost")]
    auto = radarsnn.compile_graph(g, "loihi2", calibration_inputs={"adc": cal},
                                  check_inputs={"adc": new})
    assert auto.records.accuracy.holds


# 5. The spiking CA-CFAR on linear power ------------------------------------------------------

def test_5_the_spiking_ca_cfar_on_linear_power_is_named_and_falls_back_last():
    # targets 22-35 dB below the coupling on the range-Doppler power map; the DFTs on the
    # host so the CFAR is the only spiking stage
    frames = _frames([_scene(s, (-60.0, -30.0), n=4) for s in SEEDS], SEEDS)
    g = range_doppler_chain(SMALL, cfar=CA_CFAR)
    pinned = dict(motifs={"dft": "host", "det": "time"}, calibration_inputs={"adc": frames})
    err = _refused(g, "loihi2", **pinned)
    assert err.node == "det" and "stage 'det'" in str(err)
    assert "sensitivity" in str(err) and "missed" in str(err)
    program, stage, _ = _kept(g, "loihi2", **pinned)
    assert program.records.motifs["det"] == "time" and stage.kind == "decisions"
    assert stage.figures["sensitivity"] < 0.5 and stage.figures["missed"] > 0
    auto = radarsnn.compile_graph(g, "loihi2", motifs={"dft": "host"},
                                  calibration_inputs={"adc": frames})
    sel = auto.records.extra["motif_selection"]
    assert auto.records.accuracy.holds and sel["host_ops"] == ["cfar"]
    assert [a["holds"] for a in sel["attempts"]] == [False, False, False, True]  # spiking first
