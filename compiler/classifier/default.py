r"""The shipped default classifier: its layer stack, dataset, training settings and weights file.

The stack is Vogginger et al.'s SNN (2 spiking convolutions, a recurrent LIF layer, a
non-spiking integrator) sized for its operation budget, issue #8: synaptic events at most
1 % of the conv+LSTM ANN's multiply-accumulates. Per sequence of ``T`` frames the events
are :math:`E = \sum_{\text{layers}} \sum_t s_t \cdot \text{fan-out}`, so every layer's
spikes cost its fan-out:

======================  ===========  ======================================
layer                   neurons      fan-out of one spike
======================  ===========  ======================================
input ``x > 3 dB``      32 x 32      4 (conv 4@2x2/2: non-overlapping)
conv 4@2x2/2            4 x 16 x 16  8 x 9 / 4 = 18 (conv 8@3x3/2, inside)
conv 8@3x3/2            8 x 8 x 8    1 (its max-pool OR neuron)
max pool 2x2 (OR)       8 x 4 x 4    32 (the recurrent layer)
recurrent LIF 32        32           32 + 3 (itself, delay 1; integrator)
integrator 3            3            - (never spikes)
======================  ===========  ======================================

A non-overlapping first layer keeps the input's fan-out at its channel count (the
previous ``8@5x5/2`` took ~46 per input spike, so the input alone exceeded the budget),
and the activity regulariser of :func:`compiler.classifier.fit.fit` keeps the inner
layers sparse (:data:`TRAINING`). The model is trained for 8-bit weights (:data:`MODEL`:
quantization-aware, so the shipped weights lie on the quantize pass's grid).

Examples
--------
>>> op = default_classifier()
>>> [layer.kind for layer in op.layers]
['conv2d', 'conv2d', 'pool', 'recurrent', 'integrator']
>>> op.feature_shapes("clf", ROI_SHAPE)
[(1, 32, 32), (4, 16, 16), (8, 8, 8), (8, 4, 4), (32,), (3,)]
>>> default_classifier(encoding="real").encoding.kind
'real'
"""

from __future__ import annotations

from pathlib import Path

from ir.ops.classify import (
    LIF,
    Classifier,
    Conv2d,
    Integrator,
    LevelsEncoding,
    Pool,
    RealEncoding,
    Recurrent,
)

__all__ = ["DATASET", "DEFAULT_WEIGHTS", "LEVEL_DB", "MODEL", "N_FRAMES", "ROI_SHAPE",
           "TRAINING", "default_classifier"]

#: ROI size (range bins, Doppler bins) and frames per sequence.
ROI_SHAPE: tuple[int, int] = (32, 32)
N_FRAMES: int = 8

#: The input's reference level (dB above the noise floor): a spike where ``x > LEVEL_DB``.
LEVEL_DB: float = 3.0

#: Arguments of :func:`radar.roi_dataset.make_dataset` for the shipped weights.
DATASET: dict = {"n_scenes": 3000, "seed": 2024, "roi_shape": ROI_SHAPE, "n_frames": N_FRAMES}

#: Arguments of :func:`compiler.classifier.train.snn_model` for the shipped weights: the
#: initialisation seed and quantization-aware training for 8-bit weights (Loihi's width).
MODEL: dict = {"weight_bits": 8, "seed": 0}

#: Arguments of :func:`compiler.classifier.fit.fit` for the shipped weights: the activity
#: regulariser (weight per synaptic event above the target, ramped over the epochs) and the
#: budget the kept epoch's validation events must meet (below 1 % of the ANN's 1 654 976
#: MACs with a margin for the test split and the compiled network's input delay line).
TRAINING: dict = {"epochs": 40, "lr": 3e-3, "batch_size": 64, "seed": 0,
                  "events_weight": 1e-4, "events_target": 13_000.0, "events_budget": 14_500.0}

#: The shipped weights (relative to the repository root).
DEFAULT_WEIGHTS = str(Path(__file__).resolve().parents[2] / "examples" / "classifier"
                      / "snn_default.npz")


def default_classifier(weights: str = DEFAULT_WEIGHTS, *, encoding: str = "levels",
                       level_db: float = LEVEL_DB, scale: float = 0.05) -> Classifier:
    """The default SNN: conv 4@2x2/2, conv 8@3x3/2, max pool, recurrent LIF 32, integrator.

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
    enc = LevelsEncoding(levels=(level_db,)) if encoding == "levels" \
        else RealEncoding(scale=scale)
    return Classifier(
        num_classes=3, weights=weights, encoding=enc,
        layers=(Conv2d(channels=4, kernel=(2, 2), stride=(2, 2), neuron=LIF(dv=0.25)),
                Conv2d(channels=8, kernel=(3, 3), stride=(2, 2), padding=(1, 1),
                       neuron=LIF(dv=0.25)),
                Pool(mode="max", size=(2, 2)),
                Recurrent(units=32, neuron=LIF(dv=0.125)),
                Integrator(units=3)))
