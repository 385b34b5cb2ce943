"""What a user needs to write a chain and feed it, under ``radarsnn``: the IR ops (every
class of :data:`ir.ops.OP_REGISTRY`, derived from it), the example chains, the radar
presets and the scene simulator (re-exported by the package).

Examples
--------
>>> import radarsnn
>>> config = radarsnn.preset("carrada")
>>> frame = radarsnn.simulate_frame(config, radarsnn.SCENE_PRESETS["carrada"](), seed=0)
>>> g = radarsnn.Graph(name="rd")
>>> adc = g.add(radarsnn.AdcInput(shape={"rx": 8, "chirp": 64, "sample": 256}, complex=True),
...             id="adc")
>>> rng = g.add(radarsnn.DFT(axis="sample", out_axis="range"), adc, id="rng")
>>> dop = g.add(radarsnn.DFT(axis="chirp", out_axis="doppler", shift=True), rng, id="dop")
>>> rd = g.add(radarsnn.Sum(axis="rx"), g.add(radarsnn.Magnitude(kind="square"), dop), id="rd")
>>> det = g.add(radarsnn.CFAR(kind="ca", axes=["range", "doppler"], guard=[2, 1], train=[4, 2],
...                           pfa=1e-4), rd, id="det")
>>> _ = g.add(radarsnn.Output(), det)
>>> radarsnn.evaluate(g, {"adc": frame.adc})[det].shape
(64, 256)
"""

from __future__ import annotations

from compiler.chains import range_chain, range_doppler_chain
from ir.ops import *  # noqa: F403  (the op classes; __all__ below exports those of the registry)
from ir.ops import OP_REGISTRY
from ir.ops.registry import op_classes
from radar.config import PRESETS, RadarConfig, preset
from radar.scene import SCENE_PRESETS, Scene, Target, simulate_frame, simulate_frames

__all__ = [
    *op_classes(OP_REGISTRY),
    "PRESETS", "SCENE_PRESETS", "RadarConfig", "Scene", "Target", "preset",
    "range_chain", "range_doppler_chain", "simulate_frame", "simulate_frames",
]
