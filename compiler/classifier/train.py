r"""Training the classifier and its baselines with PyTorch (optional extra ``train``; lazy import).

Models (``(n, T, H, W)`` ROI sequences in, class scores out):

* :func:`snn_model` — Vogginger et al.'s SNN built from a :class:`~ir.ops.classify.Classifier`
  op: the same update as :mod:`ir.classifier_forward.forward` (so the trained weights mean
  the same in numpy and in the compiled network), spikes through a surrogate gradient
  :math:`\partial s/\partial v = 1/(1 + \beta|v - v_{th}|)^2` (fast sigmoid), trained by
  backpropagation through time over the frames;
* :func:`cnn_model` — a CNN on single frames (conv-ReLU x2, max pool, dense-ReLU, dense);
  a sequence's prediction is the mean of its frames' logits;
* :func:`ann_model` — the same convolutions on every frame, an LSTM over the frames,
  and a dense readout of the last hidden state (real or binary ``[x > level]`` input).

:func:`compiler.classifier.fit.fit` trains any of them. :func:`fan_out` gives the synapses a
spike drives (the SNN's differentiable event count uses it), :func:`mac_counts` the
baselines' multiply-accumulates. Everything is seeded (``torch.manual_seed``) and runs on
the CPU.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ir.classifier_forward.layers import build_layer_plan
from ir.ops.classify import Classifier, Conv2d, Integrator, Pool, Recurrent

__all__ = ["ann_model", "cnn_model", "fan_out", "mac_counts", "snn_model", "snn_weights",
           "torch_module"]


def torch_module() -> Any:
    """``torch``, imported on first use (the optional extra ``train``)."""
    try:
        import torch
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError("training needs PyTorch: pip install 'radarsnn[train]' "
                          "(torch==2.13.0, CPU)") from err
    return torch


def snn_model(op: Classifier, map_shape: tuple[int, int], *, surrogate_beta: float = 5.0,
              weight_bits: int | None = None, seed: int = 0) -> Any:
    r"""A ``torch.nn.Module`` of the op's layer stack; ``state_dict`` keys = the npz keys.

    Parameters
    ----------
    op : Classifier
        The layer stack, encoding and neuron parameters (fixed, not trained).
    map_shape : (int, int)
        ROI size along ``op.map_axes``.
    surrogate_beta : float
        Steepness of the fast-sigmoid surrogate gradient.
    weight_bits : int, optional
        Quantization-aware training for a target of this many weight bits: the forward pass
        uses every population's weights rounded to the grid of the compiler's quantize pass,
        :math:`w' = s\,\mathrm{round}(w/s)` with one scale :math:`s = \max|w| / (2^{b-1}-1)`
        per population (a recurrent layer's input and recurrent weights share it), and the
        gradient passes straight through the rounding. :func:`snn_weights` then returns the
        rounded weights, which the quantize pass maps onto integers without further error.
    seed : int
        Seed of the weight initialisation.

    Returns
    -------
    torch.nn.Module
        ``forward(x)`` maps ``(n, T, H, W)`` to ``(n, classes)`` scores; after a call,
        ``.last_spikes`` holds the mean spikes per sample and ``.last_events`` the mean
        synaptic events per sample (a differentiable tensor): every input or layer spike
        times its :func:`fan_out`, plus a recurrent layer's spikes times its ``units`` at
        the next step — the count of :func:`ir.classifier_forward.forward.run_plan`.
    """
    torch = torch_module()
    nn, fnn = torch.nn, torch.nn.functional
    torch.manual_seed(seed)
    shapes = op.feature_shapes("classifier", tuple(map_shape))
    fans = [torch.as_tensor(f, dtype=torch.float32) for f in fan_out(op, tuple(map_shape))]

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

        def grid(self) -> dict:
            """The weights the forward pass uses (on the quantization grid if requested)."""
            ws = dict(self.named_parameters())
            if weight_bits is None or not ws:
                return ws
            peak = max(w.detach().abs().max() for w in ws.values())
            if peak == 0:
                return ws
            step = peak / (2 ** (weight_bits - 1) - 1)
            return {k: w + (torch.round(w.detach() / step) * step - w).detach()
                    for k, w in ws.items()}

        def current(self, x, s_prev, ws):
            lay = self.layer
            if isinstance(lay, Conv2d):
                return fnn.conv2d(x, ws["weight"], stride=lay.stride, padding=lay.padding)
            if isinstance(lay, Pool):
                pool = fnn.max_pool2d if lay.mode == "max" else fnn.avg_pool2d
                return pool(x, lay.size)
            out = x.flatten(1) @ ws["weight"].T
            if isinstance(lay, Recurrent):
                out = out + s_prev @ ws["recurrent"].T
            return out

    class SNN(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.layers = nn.ModuleList(
                [Layer(shapes[i], shapes[i + 1], layer) for i, layer in enumerate(op.layers)])
            self.last_spikes = 0.0
            self.weight_bits = weight_bits

        def grid_weights(self) -> dict:
            """``layers.<i>.<name>`` -> the weight tensors the forward pass uses."""
            return {f"layers.{i}.{k}": w for i, mod in enumerate(self.layers)
                    for k, w in mod.grid().items()}

        def forward(self, x):
            n, steps = x.shape[:2]
            x = encode(x)
            ws = [mod.grid() for mod in self.layers]
            state = [None] * len(self.layers)
            spikes = torch.zeros((), dtype=x.dtype)
            events = (x * fans[-1]).sum() if op.encoding.kind == "levels" else 0.0
            for t in range(steps):
                h = x[:, t]
                for k, mod in enumerate(self.layers):
                    lay = mod.layer
                    if isinstance(lay, Pool):
                        h = mod.current(h, None, ws[k])
                        if lay.mode == "max":
                            events = events + (h * fans[k]).sum()
                        continue
                    u, v, s = state[k] if state[k] is not None else (0.0, 0.0, torch.zeros(
                        n, lay.units, dtype=x.dtype) if isinstance(lay, Recurrent) else None)
                    par = lay if isinstance(lay, Integrator) else lay.neuron
                    if isinstance(lay, Recurrent):  # last step's spikes arrive (all-to-all)
                        events = events + lay.units * s.sum()
                    u = (1.0 - par.du) * u + mod.current(h, s, ws[k])
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
                    events = events + (s * fans[k]).sum()
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


def fan_out(op: Classifier, map_shape: tuple[int, int]) -> list[np.ndarray]:
    """Synapses driven by one spike of each neuron: per layer output, last entry the input.

    Entry ``k`` has the shape of layer ``k``'s output features (zeros for layers whose
    output is not a population: an ``avg`` pool, the integrator) and counts the wired
    synapses of the next population in :func:`ir.classifier_forward.layers.build_layer_plan`
    (all-ones weights) that a spike of that neuron drives. A recurrent layer's spikes also
    reach its own ``units`` neurons one step later (not included here).

    Examples
    --------
    >>> from ir.ops.classify import Conv2d, Integrator, LevelsEncoding
    >>> op = Classifier(num_classes=2, weights="w", encoding=LevelsEncoding(levels=(0.0,)),
    ...                 layers=(Conv2d(channels=3, kernel=(2, 1)), Integrator(units=2)))
    >>> [f.tolist() for f in fan_out(op, (3, 1))]
    [[[[2.0], [2.0]], [[2.0], [2.0]], [[2.0], [2.0]]], [0.0, 0.0], [[[3.0], [6.0], [3.0]]]]
    """

    shapes = op.feature_shapes("classifier", map_shape)
    ones = {k: np.ones(v) for k, v in op.weight_shapes("classifier", map_shape).items()}
    plans = build_layer_plan(op, ones, map_shape)
    out = [np.zeros(shape) for shape in shapes[1:]] + [np.zeros(shapes[0])]
    for p in plans:
        prev = max((q.index for q in plans if q.index < p.index), default=-1)
        out[prev] = out[prev] + np.diff(p.matrix.indptr).reshape(shapes[prev + 1])
    return out


def snn_weights(model: Any) -> dict[str, np.ndarray]:
    """The weights the model computes with, as the npz mapping (``layers.<i>.weight`` /
    ``.recurrent``): on the quantization grid for a ``weight_bits`` model."""
    return {k: v.detach().cpu().numpy().astype(np.float64)
            for k, v in model.grid_weights().items()}


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
    torch = torch_module()
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
    torch = torch_module()
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
