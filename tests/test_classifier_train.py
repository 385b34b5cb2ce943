"""A tiny training run, and the torch SNN computing what the numpy forward pass computes."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from compiler.classifier import classify  # noqa: E402
from compiler.classifier.fit import fit  # noqa: E402
from compiler.classifier.train import (  # noqa: E402
    ann_model,
    cnn_model,
    fan_out,
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
    # the differentiable event count of the regulariser is the forward pass's count
    assert np.isclose(float(model.last_events) * len(x), ref.synaptic_events.sum(), rtol=1e-6)


def test_quantization_aware_weights_lie_on_the_grid() -> None:
    model = snn_model(OP, (8, 12), weight_bits=4, seed=3)  # 4 bits: levels -7..7
    w = snn_weights(model)
    for keys in (["layers.0.weight"], ["layers.2.weight", "layers.2.recurrent"],
                 ["layers.3.weight"]):  # one scale per population (recurrence shares it)
        step = max(np.abs(w[k]).max() for k in keys) / 7
        for k in keys:
            q = w[k] / step
            assert np.allclose(q, np.rint(q), atol=1e-4) and np.abs(q).max() <= 7 + 1e-4
        raw = model.state_dict()[keys[0]].numpy()
        assert not np.allclose(raw, w[keys[0]])  # the trained (master) weights are not
    x, y = _toy(16, 0)
    scores = model(torch.as_tensor(x))
    ref = classify(OP, w, x)
    assert np.allclose(scores.detach().numpy(), ref.scores, atol=1e-4)
    torch.nn.functional.cross_entropy(scores, torch.as_tensor(y)).backward()
    grads = {k: p.grad for k, p in model.named_parameters()}
    # the gradient passes straight through the rounding (the untrained recurrent layer is
    # silent, so only the layers before it get one here)
    assert grads["layers.0.weight"].abs().sum() > 0 and grads["layers.2.weight"].abs().sum() > 0


def test_fan_out_by_hand() -> None:
    # 8 x 12 input, conv 2@3x3/2 pad 1 -> 2 x 4 x 6; pool 2x2 -> 2 x 2 x 3 OR neurons
    fans = fan_out(OP, (8, 12))
    assert [f.shape for f in fans] == [(2, 4, 6), (2, 2, 3), (6,), (3,), (1, 8, 12)]
    # output y reads input rows 2y-1..2y+1: an odd row is in 2 windows, an even row in 1
    assert fans[-1][0, 3, 3] == 2 * 2 * 2 and fans[-1][0, 2, 2] == 2 * 1 * 1
    assert fans[-1][0, 3, 11] == 2 * 2 * 1  # last column: window 6 would be past the edge
    assert np.all(fans[0] == 1) and np.all(fans[1] == 6) and np.all(fans[2] == 3)


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
    assert res.val_accuracy == res.history[res.best_epoch][1]


def test_events_budget_keeps_an_epoch_within_it(one_thread) -> None:
    model = snn_model(OP, (8, 12), seed=0)
    free = fit(model, _toy(64, 1), _toy(32, 2), epochs=6, batch_size=16, lr=2e-2, seed=0)
    events = [h[2] for h in free.history]
    budget = float(np.median(events))
    model = snn_model(OP, (8, 12), seed=0)
    res = fit(model, _toy(64, 1), _toy(32, 2), epochs=6, batch_size=16, lr=2e-2, seed=0,
              events_budget=budget)
    assert res.history == free.history  # the budget only changes which epoch is kept
    within = [(acc, -e) for _, acc, e in res.history if e <= budget]
    assert res.val_events <= budget and res.val_accuracy == max(within)[0]
    # no epoch within a budget of 0: the one with the fewest events
    model = snn_model(OP, (8, 12), seed=0)
    res = fit(model, _toy(64, 1), _toy(32, 2), epochs=6, batch_size=16, lr=2e-2, seed=0,
              events_budget=0.0)
    assert res.val_events == min(events)


def test_events_regulariser_holds_activity_near_its_target(one_thread) -> None:
    runs = []
    for weight in (0.0, 0.02):  # the hinge only acts above 250 events per sample
        model = snn_model(OP, (8, 12), seed=0)
        runs.append(fit(model, _toy(96, 1), _toy(48, 2), epochs=8, batch_size=16, lr=2e-2,
                        seed=0, events_weight=weight, events_target=250.0))
    free, held = (r.history[-1] for r in runs)
    assert free[2] > 300 and held[2] <= 250 * 1.05  # ~360 without, ~245 with the penalty
    assert held[1] >= 0.8  # and the network still learns


def test_baselines_run_and_count_macs() -> None:
    x, y = _toy(8, 0)
    xt = torch.as_tensor(x)
    assert cnn_model((8, 12))(xt).shape == (8, 3)
    assert ann_model((8, 12), level=0.5)(xt).shape == (8, 3)
    macs = mac_counts((32, 32), 8)
    # conv 8 x 16 x 16 x 25 + 16 x 8 x 8 x 72 = 124 928; LSTM 4 x 64 x (256 + 64) = 81 920
    assert macs["ann"] == 8 * (124_928 + 81_920) + 64 * 3
