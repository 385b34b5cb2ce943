r"""Fitting the classifier models: Adam + cross-entropy, best validation epoch, activity budget.

:func:`fit` trains any model of :mod:`compiler.classifier.train` (SNN, CNN, ANN) on ROI
sequences; for an SNN it can add the activity regulariser (its differentiable synaptic
events, ``model.last_events``) and keep only epochs within an events budget.
:func:`evaluate_model`, :func:`predict` and :func:`accuracy` run a model without gradients.
Everything is seeded and runs on the CPU (extra ``train``: torch).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from compiler.classifier.train import torch_module

__all__ = ["FitResult", "accuracy", "evaluate_model", "fit", "predict"]


@dataclass
class FitResult:
    """The trained model and the epoch kept (best validation accuracy within the budget).

    ``history`` holds per epoch ``(train loss, val accuracy, val events per sample)``
    (events ``nan`` for models that do not count them).
    """

    model: Any
    val_accuracy: float
    best_epoch: int
    history: list[tuple[float, float, float]]
    val_events: float = float("nan")


def fit(model: Any, train: tuple[np.ndarray, np.ndarray], val: tuple[np.ndarray, np.ndarray],
        *, epochs: int = 20, batch_size: int = 64, lr: float = 3e-3, seed: int = 0,
        frames_loss: bool = False, events_weight: float = 0.0, events_target: float = 0.0,
        events_budget: float | None = None, log: Any = None) -> FitResult:
    r"""Adam + cross-entropy over shuffled mini-batches; keep the best validation epoch.

    Parameters
    ----------
    model : torch.nn.Module
        Maps ``(n, T, H, W)`` float32 to logits.
    train, val : (x, y)
        ROI sequences and labels.
    epochs, batch_size, lr, seed : training settings.
    frames_loss : bool
        Train a frame model (``model.frames``) on every frame's label (the CNN).
    events_weight, events_target : float
        Activity regulariser of an SNN: with ``E`` its mean synaptic events per sample in
        the batch (``model.last_events``, differentiable through the surrogate gradient),
        the loss gets :math:`w\,r_e \max(0, E - E_{target})` where the ramp
        :math:`r_e = e / (\text{epochs} - 1)` grows from 0 at the first epoch to 1 at the
        last, so the penalty does not silence the network before it has learnt.
    events_budget : float, optional
        Keep the epoch of best validation accuracy among those whose mean validation events
        are at most this (the SNN's operation budget); if no epoch meets it, the epoch with
        the fewest events.
    log : callable, optional
        Called with one line per epoch.

    Returns
    -------
    FitResult
    """
    torch = torch_module()
    torch.manual_seed(seed)
    gen = np.random.default_rng(seed)
    x_tr, y_tr = torch.as_tensor(train[0], dtype=torch.float32), torch.as_tensor(train[1])
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, max(1, epochs))
    best_key, best_state, best_epoch, history = None, None, -1, []
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
                excess = torch.clamp(model.last_events - events_target, min=0.0)
                loss = loss + events_weight * ramp * excess
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
        sched.step()
        acc, events = evaluate_model(model, *val)
        history.append((total / len(order), acc, events))
        if log is not None:
            log(f"epoch {epoch:3d} loss {total / len(order):.4f} val {acc:.4f} "
                f"events {events:.0f}")
        within = events_budget is None or events <= events_budget
        key = (within, acc if within else -events)
        if best_key is None or key > best_key:
            best_key, best_epoch, best_state = key, epoch, copy.deepcopy(model.state_dict())
    model.load_state_dict(best_state)
    _, acc, events = history[best_epoch]
    return FitResult(model=model, val_accuracy=acc, best_epoch=best_epoch, history=history,
                     val_events=events)


def evaluate_model(model: Any, x: np.ndarray, y: np.ndarray,
             batch_size: int = 256) -> tuple[float, float]:
    """Accuracy and mean synaptic events per sample (``nan`` if the model counts none)."""
    torch = torch_module()
    model.eval()
    hits, events = 0, 0.0
    with torch.no_grad():
        for start in range(0, len(x), batch_size):
            xb = torch.as_tensor(x[start:start + batch_size], dtype=torch.float32)
            hits += int((model(xb).argmax(dim=1).numpy() == y[start:start + len(xb)]).sum())
            events += float(getattr(model, "last_events", float("nan"))) * len(xb)
    n = max(1, len(y))
    return hits / n, events / n


def predict(model: Any, x: np.ndarray, batch_size: int = 256) -> np.ndarray:
    """Class predictions of a model (eval mode, no gradients)."""
    torch = torch_module()
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
