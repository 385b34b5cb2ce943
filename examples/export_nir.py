"""Export a compiled radar stage to NIR and print the export report.

Compiles a small CA-CFAR over a 32 x 16 range-Doppler map to spikes, exports its
spiking network with :func:`backends.nir.export_program`, writes ``cfar.nir`` and
``cfar.report.json`` into the output folder (default: a temporary one), reads the
file back with the real ``nir`` package and lists the node types.

Run ``python examples/export_nir.py [--out DIR]``.
"""

from __future__ import annotations

import argparse
import tempfile
from collections import Counter
from pathlib import Path

import nir
import numpy as np

from backends.nir import export_program, write_nir
from compiler.compile import compile_graph
from ir import Graph


def cfar_graph() -> Graph:
    """A CA-CFAR stage on a 32 x 16 power map."""
    return Graph.from_dict({"name": "cfar32x16", "nodes": [
        {"id": "rd", "op": "input", "shape": {"range": 32, "doppler": 16}, "domain": "power"},
        {"id": "det", "op": "cfar", "input": "rd", "kind": "ca", "guard": [1, 1],
         "train": [2, 2], "alpha": 3.0, "edge": ["clip", "wrap"]},
        {"id": "out", "op": "output", "input": "det"}]})


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=None, help="output folder")
    args = parser.parse_args(argv)
    maps = np.random.default_rng(0).exponential(1.0, size=(32, 16))
    program = compile_graph(cfar_graph(), target=None, calibration_inputs={"rd": maps},
                            time_steps=64, options={"cfar_range": (0.01, 8.0)})
    graph, report = export_program(program, stages=["det"])
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.out or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        write_nir(graph, report, folder / "cfar.nir")
        back = nir.read(folder / "cfar.nir")
        print(f"wrote {folder / 'cfar.nir'} and {folder / 'cfar.report.json'} "
              f"(nir {nir.version})")
        print("node types:", dict(sorted(Counter(type(n).__name__
                                                 for n in back.nodes.values()).items())))
        print(report.summary())


if __name__ == "__main__":
    main()
