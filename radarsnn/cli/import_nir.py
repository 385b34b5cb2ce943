"""The ``radarsnn import-nir`` sub-command: a NIR file back as network artifacts.

``radarsnn import-nir X.nir -o DIR [--dt-s S] [--n-steps N]`` reads the file within
bounds (:func:`backends.nir.read_nir`) and its spiking networks
(:func:`backends.nir.import_nir`): a graph ``radarsnn export-nir`` wrote comes back
exactly; any other graph of the NIR subset (docs/interop.md) with the step ``--dt-s``
and the window ``--n-steps``.  One network is saved as the artifact ``DIR``
(:func:`backends.save`, run it with ``radarsnn run DIR``); several (a program's) as
``DIR/n0``, ``DIR/n1`` … in the graph's order.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from radarsnn.cli.export_nir import _require_nir

__all__ = ["add_parsers", "import_nir_file"]


def import_nir_file(args: argparse.Namespace) -> list[tuple[Path, object]]:
    """Read ``args.nir`` and save its networks under ``args.output``; ``[(folder, network)]``.

    Raises
    ------
    RadarSNNError
        ``nir`` is not installed.
    ArtifactError
        An unreadable or hostile file, radarsnn metadata that does not form a network, or
        a folder that cannot be written.
    IRError
        A graph outside the NIR subset (naming the NIR node).
    """
    _require_nir("import-nir")
    from backends import save
    from backends.nir import import_nir

    nets = import_nir(args.nir, dt_s=args.dt_s, n_steps=args.n_steps)
    out = Path(args.output)
    folders = [out] if len(nets) == 1 else [out / f"n{k}" for k in range(len(nets))]
    for folder, net in zip(folders, nets, strict=True):
        folder.parent.mkdir(parents=True, exist_ok=True)
        save(net, folder, extra={"imported_from": str(args.nir)})
    return list(zip(folders, nets, strict=True))


def _cmd_import_nir(args: argparse.Namespace) -> int:
    saved = import_nir_file(args)
    rows = [{"artifact": str(folder), "network": net.name, "populations": len(net.populations),
             "projections": len(net.projections), "n_steps": net.n_steps}
            for folder, net in saved]
    if args.json:
        print(json.dumps({"nir": str(args.nir), "artifacts": rows}, sort_keys=True))
    elif not args.quiet:
        for row in rows:
            print(f"wrote {row['artifact']}: network {row['network']!r} ({row['populations']} "
                  f"populations, {row['projections']} projections, {row['n_steps']} steps)")
    return 0


def add_parsers(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``import-nir`` sub-command to ``subparsers``.

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="radarsnn")
    >>> p = add_parsers(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["import-nir", "x.nir", "-o", "net"])
    >>> str(args.nir), args.output, args.dt_s, args.n_steps
    ('x.nir', 'net', None, 100)
    """
    p = subparsers.add_parser("import-nir", help="read a NIR file back as network artifacts "
                                                 "(radarsnn's exports exactly; nir extra)")
    p.add_argument("nir", type=Path, metavar="X.nir", help="the NIR file")
    p.add_argument("--output", "-o", required=True, metavar="DIR",
                   help="artifact folder (DIR/n<k> for each network of a several-network graph)")
    p.add_argument("--dt-s", type=float, default=None, metavar="SECONDS",
                   help="step of a graph without radarsnn_dt_s metadata (not radarsnn's own)")
    p.add_argument("--n-steps", type=int, default=100, metavar="N",
                   help="steps per run of a graph that is not radarsnn's own (default 100)")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing")
    p.set_defaults(func=_cmd_import_nir)
    return p
