"""Reproduce the shipped classifier weights ``examples/classifier/snn_default.npz`` (seeded).

Generates the synthetic ROI dataset (:data:`compiler.classifier.default.DATASET`), trains the
default SNN (spike input, :func:`compiler.classifier.default.default_classifier`) with BPTT and
a surrogate gradient, keeps the best validation epoch, and writes the weights and a small
JSON of its figures next to them.  Needs the ``train`` extra (torch).

Usage::

    python examples/train_classifier.py [--epochs 12] [--out examples/classifier]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small products: one BLAS thread is faster

import argparse
import json
import time
from pathlib import Path


def main() -> None:
    import torch

    from compiler.classifier.default import DATASET, ROI_SHAPE, default_classifier
    from compiler.classifier.train import accuracy, fit, snn_model, snn_weights
    from compiler.classifier.weights import save_weights
    from radar.roi_dataset import make_dataset

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=12)
    parser.add_argument("--lr", type=float, default=3e-3)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "classifier")
    args = parser.parse_args()
    torch.set_num_threads(1)
    t0 = time.time()
    ds = make_dataset(**DATASET)
    t_data = time.time() - t0
    parts = {s: ds.subset(s) for s in ("train", "val", "test")}
    print(f"dataset: {ds.x.shape[0]} sequences in {t_data:.0f} s; "
          + ", ".join(f"{s} {p.x.shape[0]}" for s, p in parts.items()))
    op = default_classifier()
    model = snn_model(op, ROI_SHAPE, seed=0)
    t1 = time.time()
    result = fit(model, (parts["train"].x, parts["train"].y), (parts["val"].x, parts["val"].y),
                 epochs=args.epochs, lr=args.lr, seed=0, log=print)
    t_train = time.time() - t1
    test = accuracy(model, parts["test"].x, parts["test"].y)
    args.out.mkdir(parents=True, exist_ok=True)
    save_weights(args.out / "snn_default.npz", snn_weights(model))
    info = {"dataset": {k: list(v) if isinstance(v, tuple) else v for k, v in DATASET.items()},
            "epochs": args.epochs, "lr": args.lr, "best_epoch": result.best_epoch,
            "val_accuracy": result.val_accuracy, "test_accuracy_torch": test,
            "dataset_seconds": round(t_data, 1), "train_seconds": round(t_train, 1),
            "torch": torch.__version__}
    (args.out / "snn_default.json").write_text(json.dumps(info, indent=2) + "\n")
    print(json.dumps(info, indent=2))


if __name__ == "__main__":
    main()
