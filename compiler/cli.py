"""The ``radarsnn`` command line: ``validate``, ``schema``, ``demo``, ``report``, ``run``.

Each sub-command is one small function; errors from the project's hierarchy
are printed as one line (``error: …``) with exit status 2, never a traceback.

Examples
--------
>>> main(["schema"]) == 0  # doctest: +ELLIPSIS
{...
True
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from ir.errors import RadarSNNError

__all__ = ["main", "build_parser"]


def _cmd_validate(args: argparse.Namespace) -> int:
    from ir import Graph

    for path in args.chains:
        graph = Graph.from_yaml(path)
        graph.verify()
        types = graph.infer_types()
        if args.json:
            print(json.dumps({"chain": str(path), "name": graph.name, "ok": True,
                              "nodes": len(types)}))
            continue
        print(f"{path}: chain {graph.name!r} is valid ({len(types)} nodes)")
        for node_id in graph.topological_order():
            t = types[node_id]
            axes = " × ".join(f"{a}:{n}" for a, n in t.axes.items())
            kind = "complex" if t.complex else "real"
            print(f"  {node_id:<12} {graph.op(node_id).op:<12} [{axes}] {kind} {t.domain}")
    return 0


def _cmd_schema(args: argparse.Namespace) -> int:
    from ir import chain_schema

    text = json.dumps(chain_schema(), indent=2, sort_keys=True)
    if args.output:
        Path(args.output).write_text(text + "\n", encoding="utf-8")
    else:
        print(text)
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from compiler.demo import run_demo

    report = run_demo(seed=args.seed, presets=args.preset)
    print(report.to_json() if args.json else report.to_text())
    return 0


def _load_arrays(items: list[str], ports: list[str], what: str) -> dict:
    """``[PORT=]FILE.npy`` arguments → arrays by port (a bare file needs exactly one port)."""
    import numpy as np

    arrays = {}
    for item in items:
        port, sep, path = item.rpartition("=")
        if not sep:
            if len(ports) != 1:
                raise RadarSNNError(f"{what} has input ports {ports}; name one as PORT=FILE.npy "
                                    f"(got {item!r})")
            port, path = ports[0], item
        try:
            arrays[port] = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as err:
            raise RadarSNNError(f"cannot read input {path!r} for port {port!r}: {err}") from None
    return arrays


def _cmd_report(args: argparse.Namespace) -> int:
    from compiler.calibration import synthetic_inputs
    from compiler.compile import compile_graph
    from ir import Graph

    graph = Graph.from_yaml(args.chain)
    if args.calibration:
        calibration = _load_arrays(args.calibration, graph.input_ids(), f"chain {args.chain}")
        note = "calibrated on the given inputs"
    else:
        calibration = synthetic_inputs(graph, seed=0)
        note = ("calibrated on synthetic noise (resources are exact; pass --calibration for "
                "thresholds that mean something on radar data)")
    motifs = dict(m.split("=", 1) for m in args.motif or [])
    program = compile_graph(graph, target=args.target, motifs=motifs,
                            calibration_inputs=calibration, time_steps=args.time_steps,
                            options={"repetitions": args.repetitions})
    report = program.records["report"]
    if args.core_map:
        report.save_core_map(args.core_map)
    if args.format == "json":
        print(report.to_json())
    else:
        print(report.to_markdown())
        print(f"\n_{note}._")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    import numpy as np

    from backends import load
    from backends.reference import simulate

    network = load(args.artifact)
    inputs = _load_arrays(args.input, [e.port for e in network.encoders],
                          f"artifact {args.artifact}")
    result = simulate(network, inputs, mode=args.mode)
    if args.output:
        np.savez(args.output, **result.outputs)
    if args.json:
        print(json.dumps({"mode": result.mode, "n_steps": result.n_steps,
                          "spike_counts": result.spike_counts,
                          "synaptic_events": result.synaptic_events,
                          "outputs": {k: list(v.shape) for k, v in result.outputs.items()}},
                         sort_keys=True))
    else:
        print(result.summary())
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``radarsnn`` command."""
    parser = argparse.ArgumentParser(
        prog="radarsnn",
        description="Compile automotive-radar DSP chains into spiking neural networks.")
    parser.add_argument("--version", action="version", version=f"radarsnn {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("validate", help="check chain files and print their inferred types")
    p.add_argument("chains", nargs="+", type=Path, metavar="CHAIN.yaml")
    p.add_argument("--json", action="store_true", help="one JSON line per chain")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("schema", help="print the JSON schema of chain files")
    p.add_argument("-o", "--output", help="write the schema to this file instead")
    p.set_defaults(func=_cmd_schema)

    p = sub.add_parser("demo", help="simulate radar scenes and run the chain on them")
    p.add_argument("--seed", type=int, default=0, help="scene noise seed (default 0)")
    p.add_argument("--preset", action="append", choices=["seed003", "carrada"],
                   help="radar preset(s) to run (default: both)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("report", help="compile a chain for a target and print what it costs")
    p.add_argument("chain", type=Path, metavar="CHAIN.yaml")
    p.add_argument("--target", "-t", default="loihi2",
                   help="built-in profile (loihi, loihi2, spinnaker2, unbounded) or a YAML file")
    p.add_argument("--format", choices=["md", "json"], default="md")
    p.add_argument("--calibration", "-c", action="append", metavar="[NODE=]X.npy",
                   help="calibration input per input node (default: synthetic noise)")
    p.add_argument("--motif", "-m", action="append", metavar="NODE_OR_OP=MOTIF",
                   help="motif choice, e.g. dft=time-fft or mag=host (repeatable)")
    p.add_argument("--time-steps", type=int, help="override the per-motif time window")
    p.add_argument("--core-map", metavar="PNG", help="also draw the core placement map")
    p.add_argument("--repetitions", choices=["auto", "spatial", "temporal"], default="auto",
                   help="repeated stages: unrolled (spatial), one instance run R times per "
                        "frame (temporal), or spatial where it fits (auto, default)")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("run", help="simulate a saved artifact on .npy inputs")
    p.add_argument("artifact", type=Path, metavar="ARTIFACT_DIR")
    p.add_argument("--input", "-i", action="append", required=True, metavar="[PORT=]X.npy",
                   help="input array per port (repeat for several ports)")
    p.add_argument("--mode", choices=["step", "closed", "auto"], default="auto")
    p.add_argument("--output", "-o", help="write decoded outputs to this .npz")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=_cmd_run)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("radarsnn")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 on a radarsnn error)."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except RadarSNNError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
