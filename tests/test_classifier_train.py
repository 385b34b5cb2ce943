"""A tiny training run, and the torch SNN computing what the numpy forward pass computes."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from compiler.classifier import classify  # noqa: E402
from compiler.classifier.train import (  # noqa: E402
    ann_model,
    cnn_model,
    fit,
    mac_counts,
    snn_model,
    snn_weights,
)
from ir.ops.classify import LIF, Classifier, Conv2d, Integrator, LevelsEncoding, Pool, Recurrent  # noqa: E402

OP = Classifier(num_classes=3, weights="w.npz", encoding=LevelsEncoding(levels=(0.5,)),
                layers=(Conv2d(channels=2, kernel=(3, 3), stride=(2, 2), padding=(1, 1),
                               neuron=LIF(dv=0.25)),
                        Pool(mode="max", size=(2, 2)),
                        Recurrent(units=6, neuron=LIF(dv=0.125, reset="value")),
                        Integrator(units=3)))


def _toy(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Class k lights a blob at column 2 + 4k of an 8 x 12 map (plus noise)."""
    rng = np.random.default_rng(seed)
    y = rng.integers(0, 3, n)
    x = rng.normal(0.0, 0.2, (n, 4, 8, 12)).astype(np.float32)
    for i, k in enumerate(y):
        x[i, :, 3:6, 1 + 4 * k:4 + 4 * k] += 1.5
    return x, y


def test_torch_snn_equals_numpy_forward() -> None:
    model = snn_model(OP, (8, 12), seed=3)
    x, _ = _toy(16, 0)
    with torch.no_grad():
        scores = model(torch.as_tensor(x, dtype=torch.float64).to(torch.float32)).numpy()
    ref = classify(OP, snn_weights(model), x)
    assert np.allclose(scores, ref.scores, atol=1e-4)
    assert np.array_equal(scores.argmax(1), ref.predictions)


@pytest.fixture
def one_thread():
    """Tiny models train fastest on one thread (and do not fight the other tests)."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


def test_tiny_training_run_learns(one_thread) -> None:
    model = snn_model(OP, (8, 12), seed=0)
    res = fit(model, _toy(96, 1), _toy(48, 2), epochs=12, batch_size=16, lr=2e-2, seed=0)
    assert res.history[-1][0] < res.history[0][0]  # the loss went down
    assert res.val_accuracy >= 0.8
    w = snn_weights(model)
    assert set(w) == set(OP.weight_shapes("c", (8, 12)))


def test_baselines_run_and_count_macs() -> None:
    x, y = _toy(8, 0)
    xt = torch.as_tensor(x)
    assert cnn_model((8, 12))(xt).shape == (8, 3)
    assert ann_model((8, 12), level=0.5)(xt).shape == (8, 3)
    macs = mac_counts((32, 32), 8)
    # conv 8 x 16 x 16 x 25 + 16 x 8 x 8 x 72 = 124 928; LSTM 4 x 64 x (256 + 64) = 81 920
    assert macs["ann"] == 8 * (124_928 + 81_920) + 64 * 3
