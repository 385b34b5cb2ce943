"""Reproduce the shipped classifier weights ``examples/classifier/snn_default.npz`` (seeded).

Generates the synthetic ROI dataset (:data:`compiler.classifier.default.DATASET`), trains the
default SNN (spike input, :func:`compiler.classifier.default.default_classifier`) with BPTT, a
surrogate gradient, 8-bit quantization-aware weights and the activity regulariser
(:data:`compiler.classifier.default.MODEL`, :data:`compiler.classifier.default.TRAINING`),
keeps the best validation epoch within the events budget, and writes the weights and a small
JSON of their figures (accuracy, spikes and synaptic events of the numpy forward pass on the
validation and test splits) next to them. Needs the ``train`` extra (torch); one torch thread.

Usage::

    python examples/train_classifier.py [--epochs 40] [--out examples/classifier]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small products: one BLAS thread is faster

import argparse
import json
import time
from pathlib import Path


def main() -> None:
    import numpy as np
    import torch

    from compiler.classifier import classify
    from compiler.classifier.default import (
        DATASET,
        MODEL,
        N_FRAMES,
        ROI_SHAPE,
        TRAINING,
        default_classifier,
    )
    from compiler.classifier.fit import fit
    from compiler.classifier.train import mac_counts, snn_model, snn_weights
    from ir.classifier_forward.weights import save_weights
    from radar.roi_dataset import make_dataset

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=TRAINING["epochs"])
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "classifier")
    args = parser.parse_args()
    torch.set_num_threads(1)
    t0 = time.time()
    ds = make_dataset(**DATASET)
    t_data = time.time() - t0
    parts = {s: ds.subset(s) for s in ("train", "val", "test")}
    print(f"dataset: {ds.x.shape[0]} sequences in {t_data:.0f} s; "
          + ", ".join(f"{s} {p.x.shape[0]}" for s, p in parts.items()), flush=True)
    op = default_classifier()
    settings = {**TRAINING, "epochs": args.epochs}
    model = snn_model(op, ROI_SHAPE, **MODEL)
    t1 = time.time()
    result = fit(model, (parts["train"].x, parts["train"].y), (parts["val"].x, parts["val"].y),
                 **settings, log=lambda line: print(line, flush=True))
    t_train = time.time() - t1
    weights = snn_weights(model)
    args.out.mkdir(parents=True, exist_ok=True)
    save_weights(args.out / "snn_default.npz", weights)
    ann_macs = mac_counts(ROI_SHAPE, N_FRAMES)["ann"]
    figures = {}
    for split in ("val", "test"):
        res = classify(op, weights, parts[split].x)
        figures[split] = {
            "sequences": int(parts[split].x.shape[0]),
            "accuracy": float(np.mean(res.predictions == parts[split].y)),
            "input_spikes": float(res.input_spikes.mean()),
            "spikes_per_layer": [round(float(s), 1) for s in res.spikes.mean(axis=0)],
            "synaptic_events": float(res.synaptic_events.mean()),
            "events_over_ann_macs": float(res.synaptic_events.mean() / ann_macs)}
    info = {"dataset": {k: list(v) if isinstance(v, tuple) else v for k, v in DATASET.items()},
            "model": MODEL, "training": settings, "best_epoch": result.best_epoch,
            "val_accuracy_torch": result.val_accuracy, "val_events_torch": result.val_events,
            "ann_macs": ann_macs, **figures, "dataset_seconds": round(t_data, 1),
            "train_seconds": round(t_train, 1), "total_seconds": round(time.time() - t0, 1),
            "torch": torch.__version__}
    (args.out / "snn_default.json").write_text(json.dumps(info, indent=2) + "\n")
    print(json.dumps(info, indent=2))


if __name__ == "__main__":
    main()
