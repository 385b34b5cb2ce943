"""The shipped default classifier: its layer stack, dataset settings and weights file.

Examples
--------
>>> op = default_classifier()
>>> [layer.kind for layer in op.layers]
['conv2d', 'conv2d', 'pool', 'recurrent', 'integrator']
>>> op.feature_shapes("clf", ROI_SHAPE)
[(1, 32, 32), (8, 16, 16), (16, 8, 8), (16, 4, 4), (64,), (3,)]
"""

from __future__ import annotations

from pathlib import Path

from ir.ops.classify import LIF, Classifier, Conv2d, Integrator, LevelsEncoding, Pool, Recurrent

__all__ = ["DATASET", "DEFAULT_WEIGHTS", "ROI_SHAPE", "N_FRAMES", "default_classifier"]

#: ROI size (range bins, Doppler bins) and frames per sequence.
ROI_SHAPE: tuple[int, int] = (32, 32)
N_FRAMES: int = 8

#: Arguments of :func:`radar.roi_dataset.make_dataset` for the shipped weights.
DATASET: dict = {"n_scenes": 1500, "seed": 2024, "roi_shape": ROI_SHAPE, "n_frames": N_FRAMES}

#: The shipped weights (relative to the repository root).
DEFAULT_WEIGHTS = str(Path(__file__).resolve().parents[2] / "examples" / "classifier"
                      / "snn_default.npz")


def default_classifier(weights: str = DEFAULT_WEIGHTS, *, encoding: str = "levels",
                       level_db: float = 10.0, scale: float = 0.05) -> Classifier:
    """The seed paper's SNN: 2 spiking convolutions, max pool, recurrent LIF, integrator.

    Parameters
    ----------
    weights : str
        The weights file.
    encoding : {"levels", "real"}
        Spike input ``[x > level_db]`` (dB above noise) or a real first layer ``scale · x``.
    level_db, scale : float
        The encoding's parameter.

    Returns
    -------
    Classifier
    """
    enc = LevelsEncoding(levels=(level_db,)) if encoding == "levels" else {
        "kind": "real", "scale": scale}
    return Classifier(
        num_classes=3, weights=weights, encoding=enc,
        layers=(Conv2d(channels=8, kernel=(5, 5), stride=(2, 2), padding=(2, 2),
                       neuron=LIF(dv=0.25)),
                Conv2d(channels=16, kernel=(3, 3), stride=(2, 2), padding=(1, 1),
                       neuron=LIF(dv=0.25)),
                Pool(mode="max", size=(2, 2)),
                Recurrent(units=64, neuron=LIF(dv=0.125)),
                Integrator(units=3)))
