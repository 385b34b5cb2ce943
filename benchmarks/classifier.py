"""Classifier figures: Table 2, the compiled 8-bit SNN, the Table-3 row, the acceptance checks.

1. Regenerates the synthetic ROI dataset of the shipped weights
   (``compiler.classifier.default.DATASET``) and uses its held-out test split.
2. Table-2-style table: CNN (single frames), ANN conv+LSTM (real and spike input) and
   SNN (real-valued first layer, the default stack, trained here with the shipped
   settings but no events budget) with torch; SNN (spike input) = the shipped weights,
   run by the numpy reference forward pass. Parameters, accuracy, mean spikes per
   sequence (the input's included, as in the paper), synaptic events, MACs (dense counts).
3. Compiles the SNN for ``loihi2`` (8-bit weights; the stock ``loihi`` refuses its layers'
   subtractive reset, ``docs/hardware.md``), runs the test set in the reference
   simulator (step mode) and compares with the float SNN: accuracy difference, per-sample
   agreement, and the simulator's synaptic events per sequence (every projection,
   including the input delay line that brings frame ``f`` in at step ``f``).
4. The Table-3 row of the classifier, then its acceptance checks.

Usage::

    python benchmarks/classifier.py [--epochs 12] [--snn-epochs 40] [--skip-baselines]

Needs the ``train`` extra (torch) for the baselines.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import time

import numpy as np


def _count(model) -> int:
    return int(sum(p.numel() for p in model.parameters()))


def baselines(parts: dict, epochs: int, snn_epochs: int, level_db: float) -> list[tuple]:
    """Train and evaluate CNN, ANN (real / spike) and SNN (real input) with torch."""
    import torch

    from compiler.classifier.default import (
        MODEL,
        N_FRAMES,
        ROI_SHAPE,
        TRAINING,
        default_classifier,
    )
    from compiler.classifier.fit import accuracy, fit
    from compiler.classifier.train import ann_model, cnn_model, mac_counts, snn_model, snn_weights
    from ir.classifier_forward.forward import classify

    torch.set_num_threads(1)
    tr = (parts["train"].x, parts["train"].y)
    va = (parts["val"].x, parts["val"].y)
    te = parts["test"]
    macs = mac_counts(ROI_SHAPE, N_FRAMES)
    rows = []
    cnn = fit(cnn_model(ROI_SHAPE), tr, va, epochs=epochs, frames_loss=True).model
    cnn.eval()
    with torch.no_grad():
        frames = cnn.frames(torch.as_tensor(te.x)).argmax(-1).numpy()
    frame_acc = float(np.mean(frames == te.y[:, None]))
    rows.append(("CNN (single frame)", _count(cnn), frame_acc, None, None,
                 macs["cnn_per_frame"]))
    for name, level in (("ANN (real-valued input)", None), ("ANN (spike input)", level_db)):
        ann = fit(ann_model(ROI_SHAPE, level=level), tr, va, epochs=epochs).model
        rows.append((name, _count(ann), accuracy(ann, te.x, te.y), None, None, macs["ann"]))
    op = default_classifier(encoding="real")
    settings = {**TRAINING, "epochs": snn_epochs, "events_budget": None}
    snn = fit(snn_model(op, ROI_SHAPE, **MODEL), tr, va, **settings).model
    res = classify(op, snn_weights(snn), te.x)
    rows.append(("SNN (real-valued input)", _count(snn),
                 float(np.mean(res.predictions == te.y)), float(res.spikes.sum(1).mean()),
                 float(res.synaptic_events.mean()), res.macs))
    return rows


def print_table(rows: list[tuple]) -> None:
    """The Table-2 rows: name, parameters, accuracy, spikes, synaptic events, MACs."""
    print(f"{'Architecture':26s} {'Params':>8s} {'Acc.':>7s} {'Spikes':>8s} {'Syn.ev.':>9s} "
          f"{'MACs':>10s}")
    for name, params, acc, spikes, events, macs in rows:
        def f(v, fmt):
            return format(v, fmt) if v is not None else "-".rjust(len(format(0, fmt)))
        print(f"{name:26s} {params:8d} {acc:7.1%} {f(spikes, '8.0f')} {f(events, '9.0f')} "
              f"{f(macs, '10d')}")


def main() -> None:
    from backends.reference import simulate
    from compiler.classifier import classify, load_weights
    from compiler.classifier.default import (
        DATASET,
        N_FRAMES,
        ROI_SHAPE,
        TRAINING,
        default_classifier,
    )
    from compiler.classifier.train import mac_counts
    from compiler.compile import compile_graph
    from compiler.report.classifier import classifier_row
    from radar.roi_dataset import make_dataset

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=12, help="CNN and ANN epochs")
    parser.add_argument("--snn-epochs", type=int, default=TRAINING["epochs"],
                        help="epochs of the real-input SNN (default: the shipped SNN's)")
    parser.add_argument("--skip-baselines", action="store_true")
    args = parser.parse_args()
    t0 = time.time()
    ds = make_dataset(**DATASET)
    parts = {s: ds.subset(s) for s in ("train", "val", "test")}
    te = parts["test"]
    print(f"dataset: {ds.x.shape[0]} ROI sequences {ds.x.shape[1:]} in {time.time() - t0:.0f} s;"
          f" test split {te.x.shape[0]} (classes {np.bincount(te.y).tolist()})", flush=True)

    op = default_classifier()
    weights = load_weights(op, ROI_SHAPE)
    t1 = time.time()
    ref = classify(op, weights, te.x)
    t_float = time.time() - t1
    acc_float = float(np.mean(ref.predictions == te.y))
    n_params = int(sum(w.size for w in weights.values()))
    rows = [] if args.skip_baselines else baselines(parts, args.epochs, args.snn_epochs,
                                                    op.encoding.levels[0])
    spikes = float((ref.spikes.sum(1) + ref.input_spikes).mean())  # input spikes included
    rows.append(("SNN (spike input)", n_params, acc_float, spikes,
                 float(ref.synaptic_events.mean()), None))
    ann_macs = mac_counts(ROI_SHAPE, N_FRAMES)["ann"]
    print("\nTable 2 (held-out synthetic test set)")
    print_table(rows)
    per_layer = ", ".join(f"{s:.0f}" for s in ref.spikes.mean(0)[:-1])
    print(f"SNN (spike input): input spikes {ref.input_spikes.mean():.0f} per sequence, "
          f"spikes per layer {per_layer}; synaptic events / ANN MACs = "
          f"{ref.synaptic_events.mean() / ann_macs:.3%}; float forward {t_float:.1f} s")

    graph = _graph(op)
    program = compile_graph(graph, target="loihi2")
    net = next(s.network for s in program.segments if s.kind == "spiking")
    x_in = np.transpose(te.x, (0, 1, 3, 2))  # (n, frame, doppler, range) as the chain's input
    t2 = time.time()
    # the encoder is a one-step threshold (x > level): no value is ever out of its range
    sim = simulate(net, {"roi": x_in}, mode="step", out_of_range="reject")
    t_sim = time.time() - t2
    pred_q = np.argmax(sim.outputs["cls"], axis=-1)
    acc_q = float(np.mean(pred_q == te.y))
    agree = float(np.mean(pred_q == ref.predictions))
    n = te.x.shape[0]
    events = {k: v / n for k, v in sim.synaptic_events.items()}
    total = sum(events.values())
    print(f"\nCompiled for loihi2 (8-bit weights), step simulator: accuracy {acc_q:.1%} vs float "
          f"{acc_float:.1%} (diff {100 * (acc_q - acc_float):+.2f} pp), per-sample agreement "
          f"{agree:.1%}; {n} sequences in {t_sim:.1f} s")
    print("synaptic events per sequence (simulator): "
          + ", ".join(f"{k} {v:.0f}" for k, v in events.items())
          + f"; total {total:.0f} = {total / ann_macs:.3%} of the ANN's {ann_macs} MACs")
    lowered = next(s.network for s in compile_graph(graph, target=None).segments
                   if s.kind == "spiking")
    row = classifier_row(lowered, "cls", frames=N_FRAMES)
    print("\nTable 3 row: inputs, neurons, synapses, steps/frame, instances/frame")
    print(" | ".join(row.as_table_row()))
    checks = [("SNN (spike input) accuracy >= 90 %", acc_float >= 0.90),
              ("SNN synaptic events (simulator, all projections) <= 1 % of ANN MACs",
               total <= 0.01 * ann_macs),
              ("compiled 8-bit accuracy within 1 pp of float", abs(acc_q - acc_float) <= 0.01),
              ("per-sample agreement >= 98 %", agree >= 0.98)]
    print("\nAcceptance checks")
    for name, ok in checks:
        print(f"  {'✓' if ok else '✗'} {name}")
    print(f"\ntotal {time.time() - t0:.0f} s")


def _graph(op):
    from compiler.classifier.default import N_FRAMES, ROI_SHAPE
    from ir import Graph

    shape = {"frame": N_FRAMES, "doppler": ROI_SHAPE[1], "range": ROI_SHAPE[0]}
    return Graph.from_dict({"name": "roi-classifier", "nodes": [
        {"id": "roi", "op": "input", "shape": shape, "domain": "db"},
        {"id": "cls", "op": "classifier", "input": "roi",
         **op.model_dump(mode="json", exclude={"op"})},
        {"id": "out", "op": "output", "input": "cls"}]})


if __name__ == "__main__":
    main()
