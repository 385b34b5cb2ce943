"""What ``radarsnn export-nir`` writes for the demo chain: the file's size, the report's counts
and every node's type and array shapes (the figures docs/interop.md quotes).

    python benchmarks/nir_export.py [--chain examples/chains/carrada_rd_oscfar.yaml]

The export compiles the 4 x 64 x 256 chain first (about half a minute on a shared 2-core
machine); the file is written to a temporary folder and removed.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import h5py  # noqa: E402

from radarsnn.cli import main as radarsnn  # noqa: E402


def describe(path: Path) -> list[str]:
    """One line per NIR node of ``path``: name, type and the shape of each array it holds."""
    lines = []
    with h5py.File(path, "r") as f:
        nodes = f["node/nodes"]
        for name in sorted(nodes):
            group = nodes[name]
            kind = group["type"][()].decode()
            arrays = ", ".join(f"{k} {tuple(group[k].shape)}" for k in sorted(group)
                               if isinstance(group[k], h5py.Dataset) and k != "type")
            lines.append(f"  {name}: {kind} {arrays}")
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chain", default=str(ROOT / "examples/chains/carrada_rd_oscfar.yaml"))
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "carrada.nir"
        status = radarsnn(["export-nir", args.chain, "-o", str(out), "-q"])
        if status != 0:
            raise SystemExit(f"export-nir exited {status}")
        report = json.loads(out.with_suffix(".report.json").read_text(encoding="utf-8"))
        counts = report["counts"]
        print(f"radarsnn export-nir {Path(args.chain).name}: {out.stat().st_size} bytes "
              f"({out.stat().st_size / 1e6:.1f} MB)")
        print("report entries: " + ", ".join(f"{counts[k]} {k}" for k in sorted(counts)))
        print("nodes:")
        print("\n".join(describe(out)))


if __name__ == "__main__":
    main()
