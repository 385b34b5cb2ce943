r"""Training the classifier and its baselines with PyTorch (optional extra ``train``; lazy import).

Models (``(n, T, H, W)`` ROI sequences in, class scores out):

* :func:`snn_model` — the seed paper's SNN built from a :class:`~ir.ops.classify.Classifier`
  op: the same update as :mod:`compiler.classifier.forward` (so the trained weights mean
  the same in numpy and in the compiled network), spikes through a surrogate gradient
  :math:`\partial s/\partial v = 1/(1 + \beta|v - v_{th}|)^2` (fast sigmoid), trained by
  backpropagation through time over the frames;
* :func:`cnn_model` — a CNN on single frames (conv-ReLU x2, max pool, dense-ReLU, dense);
  a sequence's prediction is the mean of its frames' logits;
* :func:`ann_model` — the same convolutions on every frame, an LSTM over the frames,
  and a dense readout of the last hidden state (real or binary ``[x > level]`` input).

:func:`fit` trains any of them with Adam and cross-entropy, keeping the weights of the
best validation epoch. :func:`mac_counts` gives the baselines' multiply-accumulates.
Everything is seeded (``torch.manual_seed``) and runs on the CPU.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from ir.ops.classify import Classifier, Conv2d, Integrator, Pool, Recurrent

__all__ = ["FitResult", "ann_model", "cnn_model", "fit", "mac_counts", "snn_model",
           "snn_weights"]


def _torch() -> Any:
    try:
        import torch
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError("training needs PyTorch: pip install 'radarsnn[train]' "
                          "(torch==2.13.0, CPU)") from err
    return torch


def snn_model(op: Classifier, map_shape: tuple[int, int], *, surrogate_beta: float = 5.0,
              seed: int = 0) -> Any:
    """A ``torch.nn.Module`` of the op's layer stack; ``state_dict`` keys = the npz keys.

    Parameters
    ----------
    op : Classifier
        The layer stack, encoding and neuron parameters (fixed, not trained).
    map_shape : (int, int)
        ROI size along ``op.map_axes``.
    surrogate_beta : float
        Steepness of the fast-sigmoid surrogate gradient.
    seed : int
        Seed of the weight initialisation.

    Returns
    -------
    torch.nn.Module
        ``forward(x)`` maps ``(n, T, H, W)`` to ``(n, classes)`` scores; after a call,
        ``.last_spikes`` holds the mean spikes per sample.
    """
    torch = _torch()
    nn, fnn = torch.nn, torch.nn.functional
    torch.manual_seed(seed)
    shapes = op.feature_shapes("classifier", tuple(map_shape))
    fan_out = _fan_out(op, tuple(map_shape))

    class Spike(torch.autograd.Function):
        @staticmethod
        def forward(ctx, x):  # x = v - v_th
            ctx.save_for_backward(x)
            return (x >= 0).to(x.dtype)

        @staticmethod
        def backward(ctx, grad):
            (x,) = ctx.saved_tensors
            return grad / (1.0 + surrogate_beta * x.abs()) ** 2

    class Layer(nn.Module):
        def __init__(self, shape_in: tuple, shape_out: tuple, layer) -> None:
            super().__init__()
            self.layer = layer
            n_in = int(np.prod(shape_in))
            if isinstance(layer, Conv2d):
                self.weight = nn.Parameter(torch.empty(layer.channels, shape_in[0],
                                                       *layer.kernel))
                nn.init.kaiming_uniform_(self.weight, a=5 ** 0.5)
            elif not isinstance(layer, Pool):
                self.weight = nn.Parameter(torch.empty(shape_out[0], n_in))
                nn.init.kaiming_uniform_(self.weight, a=5 ** 0.5)
            if isinstance(layer, Recurrent):
                self.recurrent = nn.Parameter(torch.empty(layer.units, layer.units))
                nn.init.orthogonal_(self.recurrent, gain=0.5)

        def current(self, x, s_prev):
            lay = self.layer
            if isinstance(lay, Conv2d):
                return fnn.conv2d(x, self.weight, stride=lay.stride, padding=lay.padding)
            if isinstance(lay, Pool):
                pool = fnn.max_pool2d if lay.mode == "max" else fnn.avg_pool2d
                return pool(x, lay.size)
            out = x.flatten(1) @ self.weight.T
            if isinstance(lay, Recurrent):
                out = out + s_prev @ self.recurrent.T
            return out

    class SNN(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.layers = nn.ModuleList(
                [Layer(shapes[i], shapes[i + 1], layer) for i, layer in enumerate(op.layers)])
            self.last_spikes = 0.0

        def forward(self, x):
            n, steps = x.shape[:2]
            x = encode(x)
            state = [None] * len(self.layers)
            spikes = torch.zeros((), dtype=x.dtype)
            events = fan_out[-1] * x.sum() if op.encoding.kind == "levels" else 0.0
            for t in range(steps):
                h = x[:, t]
                for k, mod in enumerate(self.layers):
                    lay = mod.layer
                    if isinstance(lay, Pool):
                        h = mod.current(h, None)
                        if lay.mode == "max":
                            events = events + fan_out[k] * h.sum()
                        continue
                    u, v, s = state[k] if state[k] is not None else (0.0, 0.0, torch.zeros(
                        n, lay.units, dtype=x.dtype) if isinstance(lay, Recurrent) else None)
                    par = lay if isinstance(lay, Integrator) else lay.neuron
                    u = (1.0 - par.du) * u + mod.current(h, s)
                    v = (1.0 - par.dv) * v + u
                    if isinstance(lay, Integrator):
                        state[k] = (u, v, None)
                        h = v
                        continue
                    s = Spike.apply(v - par.v_th)
                    if par.reset == "subtract":
                        v = v - par.v_th * s.detach()
                    else:
                        v = v * (1.0 - s.detach()) + par.v_reset * s.detach()
                    spikes = spikes + s.sum().detach()
                    events = events + fan_out[k] * s.sum()
                    state[k] = (u, v, s)
                    h = s
            self.last_spikes = float(spikes) / n
            self.last_events = events / n
            return h

    def encode(x):
        if op.encoding.kind == "real":
            return (op.encoding.scale * x)[:, :, None]
        levels = torch.tensor(op.encoding.levels, dtype=x.dtype)[None, None, :, None, None]
        return (x[:, :, None] > levels).to(x.dtype)

    return SNN()


def _fan_out(op: Classifier, map_shape: tuple[int, int]) -> list[float]:
    """Mean synapses driven by one spike of each layer's output (last entry: of an input)."""
    from compiler.classifier.plan import build_plan

    ones = {k: np.ones(v) for k, v in op.weight_shapes("classifier", map_shape).items()}
    plans = build_plan(op, ones, map_shape)
    out = [0.0] * (len(op.layers) + 1)
    for p in plans:
        mean = p.matrix.nnz / p.matrix.shape[0]
        prev = max((q.index for q in plans if q.index < p.index), default=-1)
        out[prev] += mean
        if p.recurrent is not None:
            out[p.index] += p.recurrent.nnz / p.recurrent.shape[0]
    return out


def snn_weights(model: Any) -> dict[str, np.ndarray]:
    """The model's weights as the npz mapping (``layers.<i>.weight`` / ``.recurrent``)."""
    return {k: v.detach().cpu().numpy().astype(np.float64)
            for k, v in model.state_dict().items()}


def _conv_stack(torch: Any, in_channels: int, map_shape: tuple[int, int]) -> tuple[Any, int]:
    nn = torch.nn
    stack = nn.Sequential(
        nn.Conv2d(in_channels, 8, 5, stride=2, padding=2), nn.ReLU(),
        nn.Conv2d(8, 16, 3, stride=2, padding=1), nn.ReLU(), nn.MaxPool2d(2), nn.Flatten())
    with torch.no_grad():
        width = stack(torch.zeros(1, in_channels, *map_shape)).shape[1]
    return stack, int(width)


def cnn_model(map_shape: tuple[int, int], *, scale: float = 0.05, seed: int = 0) -> Any:
    """The single-frame CNN baseline; ``forward((n, T, H, W))`` averages the frames' logits."""
    torch = _torch()
    nn = torch.nn
    torch.manual_seed(seed)

    class CNN(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.features, width = _conv_stack(torch, 1, map_shape)
            self.head = nn.Sequential(nn.Linear(width, 32), nn.ReLU(), nn.Linear(32, 3))

        def frames(self, x):  # (n, T, H, W) -> (n, T, classes)
            n, t = x.shape[:2]
            z = self.head(self.features(scale * x.reshape(n * t, 1, *x.shape[2:])))
            return z.reshape(n, t, -1)

        def forward(self, x):
            return self.frames(x).mean(dim=1)

    return CNN()


def ann_model(map_shape: tuple[int, int], *, level: float | None = None, scale: float = 0.05,
              hidden: int = 64, seed: int = 0) -> Any:
    """Conv + LSTM baseline: real input ``scale · x`` or, with ``level``, binary ``[x > level]``."""
    torch = _torch()
    nn = torch.nn
    torch.manual_seed(seed)

    class ANN(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.features, width = _conv_stack(torch, 1, map_shape)
            self.lstm = nn.LSTM(width, hidden, batch_first=True)
            self.head = nn.Linear(hidden, 3)

        def forward(self, x):
            n, t = x.shape[:2]
            x = (x > level).to(x.dtype) if level is not None else scale * x
            z = self.features(x.reshape(n * t, 1, *x.shape[2:])).reshape(n, t, -1)
            out, _ = self.lstm(z)
            return self.head(out[:, -1])

    return ANN()


def mac_counts(map_shape: tuple[int, int], n_frames: int, hidden: int = 64) -> dict[str, int]:
    """Multiply-accumulates per sequence of the baselines (dense counts, padding included).

    Examples
    --------
    >>> mac_counts((32, 32), 8)["cnn_per_frame"]
    133216
    """
    h1 = [(n + 4 - 5) // 2 + 1 for n in map_shape]
    h2 = [(n + 2 - 3) // 2 + 1 for n in h1]
    conv = 8 * h1[0] * h1[1] * 25 + 16 * h2[0] * h2[1] * 8 * 9
    width = 16 * (h2[0] // 2) * (h2[1] // 2)
    cnn = conv + width * 32 + 32 * 3
    lstm = 4 * hidden * (width + hidden)
    return {"cnn_per_frame": cnn, "ann": n_frames * (conv + lstm) + hidden * 3}


@dataclass
class FitResult:
    """The trained model, its best validation accuracy and the epoch it came from."""

    model: Any
    val_accuracy: float
    best_epoch: int
    history: list[tuple[float, float]]


def fit(model: Any, train: tuple[np.ndarray, np.ndarray], val: tuple[np.ndarray, np.ndarray],
        *, epochs: int = 20, batch_size: int = 64, lr: float = 3e-3, seed: int = 0,
        frames_loss: bool = False, events_weight: float = 0.0, log: Any = None) -> FitResult:
    """Adam + cross-entropy over shuffled mini-batches; keep the best validation epoch.

    Parameters
    ----------
    model : torch.nn.Module
        Maps ``(n, T, H, W)`` float32 to logits.
    train, val : (x, y)
        ROI sequences and labels.
    epochs, batch_size, lr, seed : training settings.
    frames_loss : bool
        Train a frame model (``model.frames``) on every frame's label (the CNN).
    events_weight : float
        Weight of the SNN's mean synaptic events per sample (``model.last_events``, through
        the surrogate gradient) added to the loss, ramped linearly from 0 at the first epoch
        to the full weight at the last: an activity regulariser that does not silence the
        network before it has learnt.
    log : callable, optional
        Called with one line per epoch.

    Returns
    -------
    FitResult
    """
    torch = _torch()
    torch.manual_seed(seed)
    gen = np.random.default_rng(seed)
    x_tr, y_tr = torch.as_tensor(train[0], dtype=torch.float32), torch.as_tensor(train[1])
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, max(1, epochs))
    best, best_state, best_epoch, history = -1.0, None, -1, []
    for epoch in range(epochs):
        model.train()
        ramp = epoch / max(1, epochs - 1)  # the activity penalty grows from 0 to its weight
        order = gen.permutation(len(y_tr))
        total = 0.0
        for start in range(0, len(order), batch_size):
            idx = torch.as_tensor(order[start:start + batch_size])
            xb, yb = x_tr[idx], y_tr[idx]
            if frames_loss:
                logits = model.frames(xb)
                loss = torch.nn.functional.cross_entropy(
                    logits.reshape(-1, logits.shape[-1]), yb.repeat_interleave(xb.shape[1]))
            else:
                loss = torch.nn.functional.cross_entropy(model(xb), yb)
            if events_weight:
                loss = loss + events_weight * ramp * model.last_events
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
        sched.step()
        acc = accuracy(model, *val)
        history.append((total / len(order), acc))
        if log is not None:
            log(f"epoch {epoch:3d} loss {total / len(order):.4f} val {acc:.4f}")
        if acc > best:
            best, best_epoch, best_state = acc, epoch, copy.deepcopy(model.state_dict())
    model.load_state_dict(best_state)
    return FitResult(model=model, val_accuracy=best, best_epoch=best_epoch, history=history)


def predict(model: Any, x: np.ndarray, batch_size: int = 256) -> np.ndarray:
    """Class predictions of a model (eval mode, no gradients)."""
    torch = _torch()
    model.eval()
    out = []
    with torch.no_grad():
        for start in range(0, len(x), batch_size):
            xb = torch.as_tensor(x[start:start + batch_size], dtype=torch.float32)
            out.append(model(xb).argmax(dim=1).numpy())
    return np.concatenate(out) if out else np.zeros(0, dtype=np.int64)


def accuracy(model: Any, x: np.ndarray, y: np.ndarray) -> float:
    """Fraction of correct predictions."""
    return float(np.mean(predict(model, x) == np.asarray(y))) if len(y) else 0.0
